/*
 * insn_count: a QEMU TCG plugin (API version 1, QEMU 7.2) that counts executed guest
 * instructions and reports the running count each time a marker instruction executes.
 * Part of texsat (MIT OR Apache-2.0); used by examples/firmware/count-insns.sh and run.sh.
 *
 *   qemu-system-arm ... -plugin insn_count.so,mark=ADDR[,mark=ADDR...][,out=FILE][,pcs=on]
 *
 * mark=ADDR  the address of a marker instruction (the first instruction of the firmware's
 *            `texsat_count_mark` / `texsat_demo_mark`, from llvm-nm; the Thumb bit is ignored).
 * out=FILE   where the lines go (default: stderr; never stdout, which carries the firmware's
 *            semihosting output).
 * pcs=on     also the executed count of every instruction address between marks.
 *
 * Output, one line each:
 *   insn_count 1                once loaded (the format version);
 *   pc ADDR N                   (pcs=on) before each mark line: instruction ADDR ran N times
 *                               since the previous mark line (only N > 0);
 *   mark ADDR TOTAL             each time the marker at ADDR executes: TOTAL instructions have
 *                               executed so far, marker instructions not included;
 *   end TOTAL                   at exit.
 * The instructions executed between two consecutive marks are the difference of their TOTALs.
 *
 * Why exact: every instruction of every translated block gets its own inline add of 1 to the
 * counter, emitted before the instruction's code, so an instruction is counted each time its
 * code is entered, whatever block it sits in and however the block is left (a block that ends
 * early, on an exception or a semihosting `bkpt`, has counted only the instructions it started).
 * A per-block add of the block's instruction count would be cheaper but counts the whole block
 * even when it exits early. Marker instructions get no add (a callback instead, which prints
 * the counter), so the figure between two marks does not depend on whether QEMU runs an
 * instruction's callback before or after its inline add. One vCPU (mps2-an386): the adds need
 * no atomics.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qemu_plugin_api.h"

QEMU_PLUGIN_EXPORT int qemu_plugin_version = QEMU_PLUGIN_VERSION;

#define MAX_MARKS 8
static uint64_t marks[MAX_MARKS];
static int n_marks;
static uint64_t total; /* executed instructions, markers excluded */
static FILE *out;

/* pcs=on: one counter per instruction address, in an open-addressing table that never moves
 * (QEMU keeps the counters' addresses in the translated code). */
#define SLOT_BITS 20
#define N_SLOTS (1u << SLOT_BITS)
struct slot {
    uint64_t pc;    /* address + 1; 0 = free */
    uint64_t count; /* executions since the last mark line */
};
static struct slot *slots;
static uint32_t *used; /* indices of the occupied slots, in first-translation order */
static uint32_t n_used;

static struct slot *slot_for(uint64_t pc)
{
    uint32_t i = (uint32_t)((pc * 0x9E3779B97F4A7C15ull) >> (64 - SLOT_BITS));
    for (uint32_t probe = 0; probe < N_SLOTS; probe++, i = (i + 1) & (N_SLOTS - 1)) {
        if (slots[i].pc == pc + 1) {
            return &slots[i];
        }
        if (slots[i].pc == 0) {
            slots[i].pc = pc + 1;
            used[n_used++] = i;
            return &slots[i];
        }
    }
    fprintf(stderr, "insn_count: more than %u instruction addresses\n", N_SLOTS);
    exit(1);
}

static void on_mark(unsigned int vcpu_index, void *userdata)
{
    (void)vcpu_index;
    if (slots) {
        for (uint32_t k = 0; k < n_used; k++) {
            struct slot *s = &slots[used[k]];
            if (s->count) {
                fprintf(out, "pc %" PRIx64 " %" PRIu64 "\n", s->pc - 1, s->count);
                s->count = 0;
            }
        }
    }
    fprintf(out, "mark %" PRIx64 " %" PRIu64 "\n", marks[(uintptr_t)userdata], total);
}

static void on_tb_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        int m = -1;
        for (int k = 0; k < n_marks; k++) {
            if (marks[k] == pc) {
                m = k;
            }
        }
        if (m >= 0) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_mark, QEMU_PLUGIN_CB_NO_REGS,
                                                   (void *)(uintptr_t)m);
            continue;
        }
        qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &total, 1);
        if (slots) {
            qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64,
                                                       &slot_for(pc)->count, 1);
        }
    }
}

static void on_atexit(qemu_plugin_id_t id, void *userdata)
{
    (void)id;
    (void)userdata;
    fprintf(out, "end %" PRIu64 "\n", total);
    fflush(out);
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc,
                                           char **argv)
{
    (void)info;
    const char *path = NULL;
    int pcs = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (strncmp(a, "mark=", 5) == 0 && n_marks < MAX_MARKS) {
            char *end;
            marks[n_marks++] = strtoull(a + 5, &end, 0) & ~(uint64_t)1;
            if (*end || end == a + 5) {
                fprintf(stderr, "insn_count: bad address in %s\n", a);
                return 1;
            }
        } else if (strncmp(a, "out=", 4) == 0) {
            path = a + 4;
        } else if (strcmp(a, "pcs=on") == 0) {
            pcs = 1;
        } else {
            fprintf(stderr, "insn_count: unknown or excess option %s\n", a);
            return 1;
        }
    }
    out = stderr;
    if (path && !(out = fopen(path, "w"))) {
        perror(path);
        return 1;
    }
    if (pcs) {
        slots = calloc(N_SLOTS, sizeof *slots);
        used = calloc(N_SLOTS, sizeof *used);
        if (!slots || !used) {
            fprintf(stderr, "insn_count: out of memory\n");
            return 1;
        }
    }
    fprintf(out, "insn_count 1\n");
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_tb_translate);
    qemu_plugin_register_atexit_cb(id, on_atexit, NULL);
    return 0;
}
