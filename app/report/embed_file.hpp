// EMA_EMBED(name, "path"): the file at `path` linked into the binary at build time with the
// assembler's .incbin (no generator step, no size limit), as name_begin .. name_end, with a
// trailing NUL. Used at namespace scope in one .cpp per file (the report's assets, ema pick's page).
#pragma once

#define EMA_EMBED(name, path)                                   \
  __asm__(".section .rodata\n"                                  \
          ".balign 16\n"                                        \
          ".global " #name "_begin\n" #name "_begin:\n"          \
          ".incbin \"" path "\"\n"                               \
          ".global " #name "_end\n" #name "_end:\n"              \
          ".byte 0\n"                                           \
          ".previous\n");                                       \
  extern "C" const char name##_begin[];                         \
  extern "C" const char name##_end[];
