//! Integer expressions in specs: `0x180 + $NODEID`, `0x3010 + 0x100 * f + c`.
//!
//! The AST is kept (not just the value) so that `$NODEID` defaults survive into the EDS
//! (`$NODEID+0x180`) and into generated code, where the node ID is only known at boot.

use std::collections::BTreeMap;
use std::fmt;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Expr {
    Num(i64),
    NodeId,
    Var(String),
    Neg(Box<Expr>),
    Not(Box<Expr>),
    Bin(BinOp, Box<Expr>, Box<Expr>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Rem,
    Shl,
    Shr,
    And,
    Xor,
    Or,
}

impl BinOp {
    fn precedence(self) -> u8 {
        match self {
            BinOp::Or => 1,
            BinOp::Xor => 2,
            BinOp::And => 3,
            BinOp::Shl | BinOp::Shr => 4,
            BinOp::Add | BinOp::Sub => 5,
            BinOp::Mul | BinOp::Div | BinOp::Rem => 6,
        }
    }
    fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Rem => "%",
            BinOp::Shl => "<<",
            BinOp::Shr => ">>",
            BinOp::And => "&",
            BinOp::Xor => "^",
            BinOp::Or => "|",
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExprError(pub String);

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// Values of repeat variables while a template is expanded.
pub type Vars = BTreeMap<String, i64>;

#[derive(Debug, Clone, PartialEq, Eq)]
enum Tok {
    Num(i64),
    NodeId,
    Ident(String),
    Op(&'static str),
    LParen,
    RParen,
}

fn tokenize(src: &str) -> Result<Vec<Tok>, ExprError> {
    let b = src.as_bytes();
    let mut i = 0;
    let mut out = Vec::new();
    while let Some(&c) = b.get(i) {
        match c {
            b' ' | b'\t' => i += 1,
            b'(' => {
                out.push(Tok::LParen);
                i += 1;
            }
            b')' => {
                out.push(Tok::RParen);
                i += 1;
            }
            b'$' => {
                let start = i + 1;
                let end = scan(b, start, |c| c.is_ascii_alphanumeric() || c == b'_');
                let name = &src[start..end];
                if name != "NODEID" {
                    return Err(ExprError(format!("unknown variable `${name}` (only `$NODEID` exists)")));
                }
                out.push(Tok::NodeId);
                i = end;
            }
            b'0'..=b'9' => {
                let end = scan(b, i, |c| c.is_ascii_alphanumeric() || c == b'_');
                out.push(Tok::Num(parse_int(&src[i..end])?));
                i = end;
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                let end = scan(b, i, |c| c.is_ascii_alphanumeric() || c == b'_');
                out.push(Tok::Ident(src[i..end].to_string()));
                i = end;
            }
            _ => {
                let two = src.get(i..i + 2);
                let op = match two {
                    Some("<<") => "<<",
                    Some(">>") => ">>",
                    _ => match c {
                        b'+' => "+",
                        b'-' => "-",
                        b'*' => "*",
                        b'/' => "/",
                        b'%' => "%",
                        b'&' => "&",
                        b'^' => "^",
                        b'|' => "|",
                        b'~' => "~",
                        _ => {
                            let ch = src[i..].chars().next().unwrap_or('?');
                            return Err(ExprError(format!("unexpected character `{ch}` in expression")));
                        }
                    },
                };
                out.push(Tok::Op(op));
                i += op.len();
            }
        }
    }
    Ok(out)
}

fn scan(b: &[u8], mut i: usize, pred: impl Fn(u8) -> bool) -> usize {
    while b.get(i).is_some_and(|&c| pred(c)) {
        i += 1;
    }
    i
}

/// Parses an integer literal: decimal, `0x` hex or `0b` binary, `_` separators allowed.
pub fn parse_int(text: &str) -> Result<i64, ExprError> {
    let clean: String = text.chars().filter(|&c| c != '_').collect();
    let lower = clean.to_ascii_lowercase();
    let (digits, radix) = if let Some(h) = lower.strip_prefix("0x") {
        (h, 16)
    } else if let Some(b) = lower.strip_prefix("0b") {
        (b, 2)
    } else {
        (lower.as_str(), 10)
    };
    u64::from_str_radix(digits, radix).ok().and_then(|v| i64::try_from(v).ok()).ok_or_else(|| ExprError(format!("`{text}` is not an integer literal")))
}

struct Parser {
    toks: Vec<Tok>,
    pos: usize,
}

impl Parser {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos)
    }
    fn next(&mut self) -> Option<Tok> {
        let t = self.toks.get(self.pos).cloned();
        self.pos += 1;
        t
    }
    fn binop(&self) -> Option<BinOp> {
        match self.peek()? {
            Tok::Op(op) => Some(match *op {
                "+" => BinOp::Add,
                "-" => BinOp::Sub,
                "*" => BinOp::Mul,
                "/" => BinOp::Div,
                "%" => BinOp::Rem,
                "<<" => BinOp::Shl,
                ">>" => BinOp::Shr,
                "&" => BinOp::And,
                "^" => BinOp::Xor,
                "|" => BinOp::Or,
                _ => return None,
            }),
            _ => None,
        }
    }
    fn expr(&mut self, min_prec: u8) -> Result<Expr, ExprError> {
        let mut lhs = self.unary()?;
        while let Some(op) = self.binop() {
            if op.precedence() < min_prec {
                break;
            }
            self.pos += 1;
            let rhs = self.expr(op.precedence() + 1)?;
            lhs = Expr::Bin(op, Box::new(lhs), Box::new(rhs));
        }
        Ok(lhs)
    }
    fn unary(&mut self) -> Result<Expr, ExprError> {
        match self.next() {
            Some(Tok::Num(n)) => Ok(Expr::Num(n)),
            Some(Tok::NodeId) => Ok(Expr::NodeId),
            Some(Tok::Ident(name)) => Ok(Expr::Var(name)),
            Some(Tok::Op("-")) => Ok(Expr::Neg(Box::new(self.unary()?))),
            Some(Tok::Op("~")) => Ok(Expr::Not(Box::new(self.unary()?))),
            Some(Tok::LParen) => {
                let e = self.expr(0)?;
                match self.next() {
                    Some(Tok::RParen) => Ok(e),
                    _ => Err(ExprError("missing `)`".into())),
                }
            }
            Some(t) => Err(ExprError(format!("unexpected {} in expression", describe(&t)))),
            None => Err(ExprError("expression ends early".into())),
        }
    }
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(n) => format!("number {n}"),
        Tok::NodeId => "`$NODEID`".into(),
        Tok::Ident(s) => format!("`{s}`"),
        Tok::Op(o) => format!("`{o}`"),
        Tok::LParen => "`(`".into(),
        Tok::RParen => "`)`".into(),
    }
}

impl Expr {
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        let toks = tokenize(src)?;
        if toks.is_empty() {
            return Err(ExprError("empty expression".into()));
        }
        let mut p = Parser { toks, pos: 0 };
        let e = p.expr(0)?;
        match p.peek() {
            None => Ok(e),
            Some(t) => Err(ExprError(format!("unexpected {} after the expression", describe(t)))),
        }
    }

    pub fn uses_node_id(&self) -> bool {
        match self {
            Expr::NodeId => true,
            Expr::Num(_) | Expr::Var(_) => false,
            Expr::Neg(e) | Expr::Not(e) => e.uses_node_id(),
            Expr::Bin(_, a, b) => a.uses_node_id() || b.uses_node_id(),
        }
    }

    /// Evaluates with repeat variables and, if given, a node ID.
    pub fn eval(&self, vars: &Vars, node_id: Option<i64>) -> Result<i64, ExprError> {
        let overflow = || ExprError("arithmetic overflow in expression".into());
        Ok(match self {
            Expr::Num(n) => *n,
            Expr::NodeId => node_id.ok_or_else(|| ExprError("`$NODEID` is not allowed here".into()))?,
            Expr::Var(v) => *vars.get(v).ok_or_else(|| ExprError(format!("unknown variable `{v}`")))?,
            Expr::Neg(e) => e.eval(vars, node_id)?.checked_neg().ok_or_else(overflow)?,
            Expr::Not(e) => !e.eval(vars, node_id)?,
            Expr::Bin(op, a, b) => {
                let (a, b) = (a.eval(vars, node_id)?, b.eval(vars, node_id)?);
                let shift = |b: i64| u32::try_from(b).ok().filter(|&s| s < 64).ok_or_else(|| ExprError(format!("shift by {b} is out of range")));
                match op {
                    BinOp::Add => a.checked_add(b).ok_or_else(overflow)?,
                    BinOp::Sub => a.checked_sub(b).ok_or_else(overflow)?,
                    BinOp::Mul => a.checked_mul(b).ok_or_else(overflow)?,
                    BinOp::Div => a.checked_div(b).ok_or_else(|| ExprError("division by zero".into()))?,
                    BinOp::Rem => a.checked_rem(b).ok_or_else(|| ExprError("division by zero".into()))?,
                    BinOp::Shl => a.checked_shl(shift(b)?).ok_or_else(overflow)?,
                    BinOp::Shr => a >> shift(b)?,
                    BinOp::And => a & b,
                    BinOp::Xor => a ^ b,
                    BinOp::Or => a | b,
                }
            }
        })
    }

    /// Replaces repeat variables by their values, keeping `$NODEID` symbolic.
    pub fn bind(&self, vars: &Vars) -> Result<Expr, ExprError> {
        if !self.uses_node_id() {
            return Ok(Expr::Num(self.eval(vars, None)?));
        }
        Ok(match self {
            Expr::Num(_) | Expr::NodeId => self.clone(),
            Expr::Var(_) => Expr::Num(self.eval(vars, None)?),
            Expr::Neg(e) => Expr::Neg(Box::new(e.bind(vars)?)),
            Expr::Not(e) => Expr::Not(Box::new(e.bind(vars)?)),
            Expr::Bin(op, a, b) => Expr::Bin(*op, Box::new(a.bind(vars)?), Box::new(b.bind(vars)?)),
        })
    }

    /// Splits `k + $NODEID` into `k`: the only shape the EDS format (CiA 306) can carry.
    /// Returns `Ok(None)` for constants.
    pub fn node_id_offset(&self) -> Result<Option<i64>, ExprError> {
        let none = Vars::new();
        if !self.uses_node_id() {
            return Ok(None);
        }
        let base = self.eval(&none, Some(0))?;
        for n in [1_i64, 2, 64, 127] {
            if self.eval(&none, Some(n))? != base + n {
                return Err(ExprError("a `$NODEID` expression must have the form `constant + $NODEID`".into()));
            }
        }
        Ok(Some(base))
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn go(e: &Expr, f: &mut fmt::Formatter<'_>, parent: u8) -> fmt::Result {
            match e {
                Expr::Num(n) if *n >= 10 => write!(f, "{n:#X}").map(|()| ()),
                Expr::Num(n) => write!(f, "{n}"),
                Expr::NodeId => f.write_str("$NODEID"),
                Expr::Var(v) => f.write_str(v),
                Expr::Neg(e) => {
                    f.write_str("-")?;
                    go(e, f, 7)
                }
                Expr::Not(e) => {
                    f.write_str("~")?;
                    go(e, f, 7)
                }
                Expr::Bin(op, a, b) => {
                    let p = op.precedence();
                    if p < parent {
                        f.write_str("(")?;
                    }
                    go(a, f, p)?;
                    write!(f, " {} ", op.symbol())?;
                    go(b, f, p + 1)?;
                    if p < parent {
                        f.write_str(")")?;
                    }
                    Ok(())
                }
            }
        }
        go(self, f, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(s: &str) -> i64 {
        Expr::parse(s).and_then(|e| e.eval(&Vars::new(), Some(5))).unwrap_or(i64::MIN)
    }

    #[test]
    fn precedence_follows_c() {
        assert_eq!(eval("1 + 2 * 3"), 7);
        assert_eq!(eval("(1 + 2) * 3"), 9);
        assert_eq!(eval("1 << 4 | 1"), 17);
        assert_eq!(eval("0x80000000 + 0x180 + $NODEID"), 0x8000_0185);
        assert_eq!(eval("~0 & 0xFF"), 0xFF);
        assert_eq!(eval("0b1010_0101"), 0xA5);
        assert_eq!(eval("10 - 2 - 3"), 5);
    }

    #[test]
    fn errors_are_reported_not_panicked() {
        for bad in ["", "1 +", "(1", "1 / 0", "$FOO", "1 ) 2", "0xZZ", "1 << 99", "9223372036854775807 + 1", "#"] {
            let r = Expr::parse(bad).and_then(|e| e.eval(&Vars::new(), Some(1)));
            assert!(r.is_err(), "{bad} should fail");
        }
    }

    #[test]
    fn node_id_offset_accepts_only_linear_forms() {
        assert_eq!(Expr::parse("$NODEID + 0x180").ok().map(|e| e.node_id_offset()), Some(Ok(Some(0x180))));
        assert_eq!(Expr::parse("0x180").ok().map(|e| e.node_id_offset()), Some(Ok(None)));
        assert!(Expr::parse("2 * $NODEID").is_ok_and(|e| e.node_id_offset().is_err()));
    }

    #[test]
    fn bind_keeps_node_id_symbolic() {
        let mut vars = Vars::new();
        vars.insert("f".into(), 2);
        let e = Expr::parse("0x3000 + 0x100 * f").and_then(|e| e.bind(&vars));
        assert_eq!(e, Ok(Expr::Num(0x3200)));
        let e = Expr::parse("$NODEID + 0x100 * f").and_then(|e| e.bind(&vars));
        assert_eq!(e.map(|e| e.to_string()), Ok("$NODEID + 0x200".to_string()));
    }
}
