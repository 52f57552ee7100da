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
 * With `profile=PROFILE_FILE` it also writes where the instructions went: one line per guest
 * function, "COUNT SYMBOL" (the mangled name from the program's symbol table, as QEMU's loader
 * read it; "?" for code without a symbol, such as shared libraries), largest first. A block is
 * counted under the function of its first instruction. `c++filt` demangles the names.
 *
 * With `blocks=BLOCKS_FILE` it writes the hottest translated blocks (the inner loops, for
 * llvm-mca: scripts/arm-mca.sh): one line per block, "INSTRUCTIONS EXECUTIONS SIZE VADDR
 * SYMBOL" (SIZE in instructions, VADDR the guest address of its first one, in hex), largest
 * first, those making up 99 % of the instructions of blocks with a symbol, at most 2000.
 *
 * Debian's qemu-user (7.2) runs plugins but ships no <qemu-plugin.h>; the few declarations this
 * plugin needs, from QEMU's documented plugin API (version 1), are below.
 */
#include <inttypes.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t; /* only passed through */
struct qemu_plugin_tb;
struct qemu_plugin_insn;
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void* userdata);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb* tb, enum qemu_plugin_op op,
                                              void* ptr, uint64_t imm);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void* userdata);
struct qemu_plugin_insn* qemu_plugin_tb_get_insn(const struct qemu_plugin_tb* tb, size_t idx);
const char* qemu_plugin_insn_symbol(const struct qemu_plugin_insn* insn);
uint64_t qemu_plugin_tb_vaddr(const struct qemu_plugin_tb* tb);

#define EXPORT __attribute__((visibility("default")))

EXPORT int qemu_plugin_version = 1;

static uint64_t instructions;
static char out_path[4096];
static char profile_path[4096];
static char blocks_path[4096];

/* The profile: a counter per guest function, found by its symbol's address (QEMU's symbol table
 * keeps the names for the whole run), in an open-addressed table. Blocks are translated one at a
 * time (under QEMU's translation lock), so the table needs no lock of its own. */
enum { kFunctions = 1 << 16 };
struct function_count {
  const char* symbol; /* NULL: a free slot */
  uint64_t instructions;
};
static struct function_count functions[kFunctions];
static struct function_count unknown = {"?", 0};
static size_t functions_used; /* at most kFunctions - 2: one slot free, one for `unknown` */
static int functions_full;

static struct function_count* function_of(const char* symbol) {
  if (symbol == NULL) return &unknown;
  /* One slot is always free, so the probe ends. */
  size_t slot = ((uintptr_t)symbol >> 3) & (kFunctions - 1);
  while (functions[slot].symbol != NULL && functions[slot].symbol != symbol) {
    slot = (slot + 1) & (kFunctions - 1);
  }
  if (functions[slot].symbol == symbol) return &functions[slot];
  if (functions_used == kFunctions - 2) {
    functions_full = 1;
    return &unknown;
  }
  functions[slot].symbol = symbol;
  ++functions_used;
  return &functions[slot];
}

/* The block profile: an execution counter per block (its address and size: a block translated
 * again, after QEMU flushed its cache, counts on in the same one), in an open-addressed table. */
enum { kBlocks = 1 << 18 };
struct block_count {
  uint64_t vaddr;
  uint64_t size; /* instructions; 0: a free slot */
  const char* symbol;
  uint64_t executions;
};
static struct block_count blocks[kBlocks];
static size_t blocks_used; /* at most kBlocks - 1: one slot stays free */
static int blocks_full;

static struct block_count* block_of(uint64_t vaddr, uint64_t size, const char* symbol) {
  size_t slot = (size_t)((vaddr >> 2) * 0x9E3779B97F4A7C15ull >> 46) & (kBlocks - 1);
  while (blocks[slot].size != 0 && (blocks[slot].vaddr != vaddr || blocks[slot].size != size)) {
    slot = (slot + 1) & (kBlocks - 1);
  }
  if (blocks[slot].size != 0) return &blocks[slot];
  if (blocks_used == kBlocks - 1) {
    blocks_full = 1;
    return NULL;
  }
  blocks[slot] = (struct block_count){vaddr, size, symbol, 0};
  ++blocks_used;
  return &blocks[slot];
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  const size_t n = qemu_plugin_tb_n_insns(tb);
  qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &instructions, n);
  if (n == 0) return;
  const char* symbol = qemu_plugin_insn_symbol(qemu_plugin_tb_get_insn(tb, 0));
  if (profile_path[0] != '\0') {
    struct function_count* f = function_of(symbol);
    qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &f->instructions, n);
  }
  if (blocks_path[0] != '\0' && symbol != NULL) {
    struct block_count* b = block_of(qemu_plugin_tb_vaddr(tb), n, symbol);
    if (b != NULL) {
      qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &b->executions, 1);
    }
  }
}

static int by_count_descending(const void* a, const void* b) {
  const uint64_t x = ((const struct function_count*)a)->instructions;
  const uint64_t y = ((const struct function_count*)b)->instructions;
  return x < y ? 1 : x > y ? -1 : 0;
}

static void write_profile(void) {
  size_t used = 0;
  for (size_t i = 0; i < kFunctions; ++i) {
    if (functions[i].symbol != NULL) functions[used++] = functions[i];
  }
  functions[used++] = unknown; /* the table keeps one slot free for it */
  qsort(functions, used, sizeof functions[0], by_count_descending);
  FILE* f = fopen(profile_path, "w");
  int ok = f != NULL;
  for (size_t i = 0; ok && i < used; ++i) {
    if (functions[i].instructions == 0) continue;
    ok = fprintf(f, "%" PRIu64 " %s\n", functions[i].instructions, functions[i].symbol) > 0;
  }
  if (f == NULL || !ok || fclose(f) != 0) {
    fprintf(stderr, "epipole_insn_count: cannot write the profile to %s\n", profile_path);
  }
  if (functions_full) {
    fprintf(stderr, "epipole_insn_count: more than %d functions: the rest counted as '?'\n",
            kFunctions - 2);
  }
}

static int by_instructions_descending(const void* a, const void* b) {
  const struct block_count* x = a;
  const struct block_count* y = b;
  const uint64_t ix = x->executions * x->size;
  const uint64_t iy = y->executions * y->size;
  return ix < iy ? 1 : ix > iy ? -1 : 0;
}

static void write_blocks(void) {
  size_t used = 0;
  uint64_t total = 0;
  for (size_t i = 0; i < kBlocks; ++i) {
    if (blocks[i].size == 0 || blocks[i].executions == 0) continue;
    total += blocks[i].executions * blocks[i].size;
    blocks[used++] = blocks[i];
  }
  qsort(blocks, used, sizeof blocks[0], by_instructions_descending);
  FILE* f = fopen(blocks_path, "w");
  int ok = f != NULL;
  uint64_t written = 0;
  for (size_t i = 0; ok && i < used && i < 2000 && written < total / 100 * 99; ++i) {
    const uint64_t n = blocks[i].executions * blocks[i].size;
    ok = fprintf(f, "%" PRIu64 " %" PRIu64 " %" PRIu64 " %" PRIx64 " %s\n", n, blocks[i].executions,
                 blocks[i].size, blocks[i].vaddr, blocks[i].symbol) > 0;
    written += n;
  }
  if (f == NULL || !ok || fclose(f) != 0) {
    fprintf(stderr, "epipole_insn_count: cannot write the blocks to %s\n", blocks_path);
  }
  if (blocks_full) {
    fprintf(stderr, "epipole_insn_count: more than %d blocks: the rest not profiled\n",
            kBlocks - 1);
  }
}

static void report_at_exit(qemu_plugin_id_t id, void* userdata) {
  (void)id;
  (void)userdata;
  if (profile_path[0] != '\0') write_profile();
  if (blocks_path[0] != '\0') write_blocks();
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
    } else if (strncmp(argv[i], "profile=", 8) == 0 && argv[i][8] != '\0' &&
               strlen(argv[i] + 8) < sizeof profile_path) {
      strcpy(profile_path, argv[i] + 8);
    } else if (strncmp(argv[i], "blocks=", 7) == 0 && argv[i][7] != '\0' &&
               strlen(argv[i] + 7) < sizeof blocks_path) {
      strcpy(blocks_path, argv[i] + 7);
    } else {
      fprintf(stderr,
              "epipole_insn_count: unknown argument '%s' (expected out=FILE, profile=FILE, "
              "blocks=FILE)\n",
              argv[i]);
      return -1;
    }
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
  qemu_plugin_register_atexit_cb(id, report_at_exit, NULL);
  return 0;
}
