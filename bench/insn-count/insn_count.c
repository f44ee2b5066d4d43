/*
 * insn_count: a QEMU TCG plugin that counts the guest instructions executed
 * between two marker functions of the bench image.
 *
 *   qemu-system-arm ... -d plugin -plugin ./libinsn_count.so,begin=0x...,end=0x...
 *
 * Every translated instruction gets an inline "add 1" to one counter. The first
 * instruction of the begin marker and of the end marker also get a callback:
 * begin notes the counter, end prints "scenario <n>: <count> instructions",
 * n counting begin hits from 0. The count covers the instructions from the
 * begin marker's first one up to, not including, the end marker's first one:
 * the rest of the begin marker and the call of the end marker are in it, which
 * an empty scenario measures (xtask subtracts it). One vCPU (lm3s6965evb).
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qemu_plugin_api.h"

QEMU_PLUGIN_EXPORT int qemu_plugin_version = 1;

static uint64_t executed;
static uint64_t begin_addr, end_addr, started_at;
static unsigned scenario;
static int inside;

static void on_begin(unsigned int vcpu, void *udata)
{
    (void)vcpu, (void)udata;
    started_at = executed;
    inside = 1;
}

static void on_end(unsigned int vcpu, void *udata)
{
    char line[80];
    (void)vcpu, (void)udata;
    if (!inside)
        return;
    inside = 0;
    snprintf(line, sizeof line, "scenario %u: %" PRIu64 " instructions\n", scenario++, executed - started_at);
    qemu_plugin_outs(line);
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    (void)id;
    for (size_t i = 0, n = qemu_plugin_tb_n_insns(tb); i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t at = qemu_plugin_insn_vaddr(insn);
        /* The callback before the counter's add, in the same order at both markers. */
        if (at == begin_addr)
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_begin, QEMU_PLUGIN_CB_NO_REGS, NULL);
        else if (at == end_addr)
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_end, QEMU_PLUGIN_CB_NO_REGS, NULL);
        qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &executed, 1);
    }
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc, char **argv)
{
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "begin=", 6) == 0)
            begin_addr = strtoull(argv[i] + 6, NULL, 0);
        else if (strncmp(argv[i], "end=", 4) == 0)
            end_addr = strtoull(argv[i] + 4, NULL, 0);
    }
    if (begin_addr == 0 || end_addr == 0) {
        fprintf(stderr, "insn_count: needs begin=ADDR,end=ADDR (the marker functions)\n");
        return -1;
    }
    /* Thumb symbols carry bit 0; instruction addresses do not. */
    begin_addr &= ~(uint64_t)1;
    end_addr &= ~(uint64_t)1;
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    return 0;
}
