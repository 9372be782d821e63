// CANDI_TARGET_CLONES_AVX2: the function is compiled twice, for AVX2 and for the baseline x86-64,
// and the loader picks one for the CPU (a GNU ifunc). CANDI_TARGET_CLONES_AVX512 adds a third,
// for AVX-512F. Code under them must give the same bits on every path. AVX2 alone has no FMA,
// but AVX-512F has, and GCC contracts a * b + c into one fused (differently rounded) operation
// in C++ wherever FMA is enabled, -std=c++17 or not: a file with AVX-512 clones must be
// compiled with -ffp-contract=off (render/CMakeLists.txt does it for the packer's kernels).
//
// ThreadSanitizer builds get the baseline only: the ifunc resolver runs while the program is being
// relocated, before the TSan runtime exists, and its instrumented entry crashes there.
#pragma once

#if defined(__SANITIZE_THREAD__)
#define CANDI_TARGET_CLONES_AVX2
#define CANDI_TARGET_CLONES_AVX512
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CANDI_TARGET_CLONES_AVX2
#define CANDI_TARGET_CLONES_AVX512
#endif
#endif

#ifndef CANDI_TARGET_CLONES_AVX2
#define CANDI_TARGET_CLONES_AVX2 __attribute__((target_clones("avx2", "default")))
#endif

#ifndef CANDI_TARGET_CLONES_AVX512
#define CANDI_TARGET_CLONES_AVX512 __attribute__((target_clones("avx512f", "avx2", "default")))
#endif
