/*
 * A QEMU TCG plugin that counts the guest instructions a program executes, for exact ARM
 * figures without a board (docs/performance.md, "ARM instruction counts"):
 *
 *   qemu-aarch64 -plugin libepipole_insn_count.so,out=COUNT_FILE PROGRAM ARGS...
 *
 * At exit it writes the count (a decimal number and a newline) to COUNT_FILE, or to stderr
 * without `out=` (QEMU's qemu_plugin_outs() writes only with `-d plugin`). Each translated block
 * adds its instruction count to one 64-bit counter inline, as it runs: exact for a guest with one
 * thread. A guest's threads run as host threads under qemu-user and their additions can race, so
 * measure with one thread.
 *
 * Debian's qemu-user (7.2) runs plugins but ships no <qemu-plugin.h>; the few declarations this
 * plugin needs, from QEMU's documented plugin API (version 1), are below.
 */
#include <inttypes.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t; /* only passed through */
struct qemu_plugin_tb;
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void* userdata);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb* tb, enum qemu_plugin_op op,
                                              void* ptr, uint64_t imm);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void* userdata);

#define EXPORT __attribute__((visibility("default")))

EXPORT int qemu_plugin_version = 1;

static uint64_t instructions;
static char out_path[4096];

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &instructions,
                                           qemu_plugin_tb_n_insns(tb));
}

static void report_at_exit(qemu_plugin_id_t id, void* userdata) {
  (void)id;
  (void)userdata;
  char line[64];
  snprintf(line, sizeof line, "%" PRIu64 "\n", instructions);
  if (out_path[0] == '\0') {
    fputs(line, stderr);
    return;
  }
  FILE* f = fopen(out_path, "w");
  if (f == NULL || fputs(line, f) < 0 || fclose(f) != 0) {
    fprintf(stderr, "epipole_insn_count: cannot write the count to %s\n", out_path);
  }
}

EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc,
                               char** argv) {
  (void)info;
  for (int i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "out=", 4) == 0 && strlen(argv[i] + 4) < sizeof out_path) {
      strcpy(out_path, argv[i] + 4);
    } else {
      fprintf(stderr, "epipole_insn_count: unknown argument '%s' (expected out=FILE)\n", argv[i]);
      return -1;
    }
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
  qemu_plugin_register_atexit_cb(id, report_at_exit, NULL);
  return 0;
}
