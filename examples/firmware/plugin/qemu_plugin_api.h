/*
 * The few declarations of QEMU's TCG plugin API (API version 1) that insn_count.c uses,
 * written for texsat (MIT OR Apache-2.0) because Debian's QEMU 7.2 packages ship no
 * qemu-plugin.h.
 *
 * This file states interface facts only: names, argument types and order, enum values. Where
 * they come from:
 *   - QEMU's include/qemu/qemu-plugin.h (repository qemu/qemu) as of API version 1, the version
 *     QEMU 7.2 speaks (a later QEMU moved to version 2, removing qemu_plugin_n_vcpus and
 *     reworking the inline operations). The loader of QEMU 7.2 (plugins/loader.c) accepts a plugin whose
 *     exported `int qemu_plugin_version` lies in [QEMU_PLUGIN_MIN_VERSION, QEMU_PLUGIN_VERSION]
 *     = [0, 1], else it refuses to load it ("plugin requires API version ...").
 *   - The functions below are all exported by Debian's qemu-system-arm 7.2
 *     (`nm -D $(which qemu-system-arm) | grep qemu_plugin_`), which also exports
 *     qemu_plugin_n_vcpus: it speaks version 1.
 * The enum values: in version 1 the callback flags are NO_REGS = 0, R_REGS = 1, RW_REGS = 2,
 * and the only inline operation is INLINE_ADD_U64 = 0 (an add of a 64-bit immediate to a
 * uint64_t in memory). QEMU 7.2 emits that add whatever operation value it is given (built
 * with INLINE_ADD_U64 = 1, the plugin counted the same), so the count cannot reveal a wrong
 * value there: the values are copied from the header, not inferred.
 */
#ifndef TEXSAT_QEMU_PLUGIN_API_H
#define TEXSAT_QEMU_PLUGIN_API_H

#include <stddef.h>
#include <stdint.h>

#define QEMU_PLUGIN_EXPORT __attribute__((visibility("default")))

/* The API version this plugin is built against; the plugin exports it as `qemu_plugin_version`. */
#define QEMU_PLUGIN_VERSION 1

typedef uint64_t qemu_plugin_id_t;

/* Handed to qemu_plugin_install; this plugin does not read it (so its layout is left opaque). */
typedef struct qemu_info_t qemu_info_t;

/* Opaque handles, valid only during the translation callback. */
struct qemu_plugin_tb;
struct qemu_plugin_insn;

enum qemu_plugin_cb_flags {
    QEMU_PLUGIN_CB_NO_REGS = 0,
    QEMU_PLUGIN_CB_R_REGS = 1,
    QEMU_PLUGIN_CB_RW_REGS = 2,
};

enum qemu_plugin_op {
    QEMU_PLUGIN_INLINE_ADD_U64 = 0,
};

typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);

/* Implemented by the plugin: called once at load; argv holds the "name=value" options given
 * after the file name in `-plugin FILE,name=value,...`. Non-zero refuses the load. */
QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc,
                                           char **argv);

/* Implemented by QEMU. */
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *insn);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn,
                                            qemu_plugin_vcpu_udata_cb_t cb,
                                            enum qemu_plugin_cb_flags flags, void *userdata);
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn *insn,
                                                enum qemu_plugin_op op, void *ptr, uint64_t imm);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb,
                                    void *userdata);

#endif
