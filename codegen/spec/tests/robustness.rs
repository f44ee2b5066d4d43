//! Malformed specs must produce diagnostics, never a panic: thousands of random mutations of
//! valid specs go through loading, validation, every exporter and the formatter.

mod common;

use coforge_spec::{eds, fmt, load_str};
use common::{crate_dir, repo_dir};

/// xorshift64*: deterministic, so a failure is reproducible from its iteration number.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        usize::try_from(self.next() % (n.max(1) as u64)).unwrap_or(0)
    }
}

/// Characters that matter to YAML and to our expressions and hex strings.
const ALPHABET: &[u8] = b" :-{}[],#'\"|>\n0123456789abcdefxABCDEFX$+*()~<&_";

fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for _ in 0..=rng.below(3) {
        let len = bytes.len();
        match rng.below(5) {
            0 => {
                let at = rng.below(len);
                bytes[at] = ALPHABET[rng.below(ALPHABET.len())];
            }
            1 => {
                let at = rng.below(len);
                let end = (at + rng.below(40)).min(len);
                bytes.drain(at..end);
            }
            2 => {
                let at = rng.below(len);
                bytes.insert(at, ALPHABET[rng.below(ALPHABET.len())]);
            }
            3 => {
                // Replace a number with an extreme one.
                let at = rng.below(len);
                let end = (at + 4).min(len);
                let big: &[&[u8]] = &[b"0xFFFFFFFFFFFFFFFF", b"-1", b"99999999999999999999", b"0", b"$NODEID*0"];
                bytes.splice(at..end, big[rng.below(big.len())].iter().copied());
            }
            _ => bytes.truncate(rng.below(len)),
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Runs everything a user can run on a spec; true if the spec loaded without errors.
fn exercise(name: &str, text: &str) -> bool {
    let loaded = load_str(name, text);
    let _ = loaded.render_diagnostics();
    if let Some(d) = loaded.device() {
        for mode in d.mode_names() {
            let _ = eds::export(d, mode);
            let _ = eds::model_json(d, mode, 127);
        }
        let _ = coforge_spec::docs::markdown(d);
    }
    let _ = fmt::format(text);
    loaded.device().is_some()
}

#[test]
fn random_mutations_never_panic() {
    let sources = [
        std::fs::read_to_string(crate_dir().join("tests/fixtures/valid/minimal.yaml")).unwrap_or_default(),
        std::fs::read_to_string(repo_dir().join("spec/canopenia.yaml")).unwrap_or_default(),
    ];
    let mut rng = Rng(0x00C0_F0E6_2026_1122);
    let mut loaded_ok = 0;
    // Mostly the small fixture (it reaches every part of the format), every fourth time a
    // real spec.
    for i in 0..1000 {
        let source = &sources[usize::from(i % 4 == 3)];
        let text = mutate(source, &mut rng);
        // A panic fails the test; the iteration number identifies the input.
        match std::panic::catch_unwind(|| exercise("mutated.yaml", &text)) {
            Ok(valid) => loaded_ok += usize::from(valid),
            Err(_) => panic!("iteration {i} panicked on:\n{text}"),
        }
    }
    // Some mutations (inside descriptions) keep the spec valid: the exporters ran too.
    assert!(loaded_ok > 50, "only {loaded_ok} mutated specs stayed valid");
}
