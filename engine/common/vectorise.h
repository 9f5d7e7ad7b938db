#pragma once
// Per-pixel loops of engine/vision and engine/rows are plain C++ that GCC vectorises (the
// files are compiled with -O3). The build targets baseline x86-64 (SSE2),
// so a loop marked PLANTSCALE_VECTOR_CLONES is compiled twice, for AVX2 and
// for the baseline, and the loader picks the one the CPU runs (GCC function
// multi-versioning; other compilers get the baseline only: clang 14 cannot
// multi-version function templates, and clang builds are the fuzz build).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define PLANTSCALE_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PLANTSCALE_VECTOR_CLONES
#endif
