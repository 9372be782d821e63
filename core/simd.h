// CANDI_TARGET_CLONES_AVX2: the function is compiled twice, for AVX2 and for the baseline x86-64,
// and the loader picks one for the CPU (a GNU ifunc). Code under it must give the same bits on
// both paths (no FMA contraction: the build is ISO C++, where GCC does not contract).
//
// ThreadSanitizer builds get the baseline only: the ifunc resolver runs while the program is being
// relocated, before the TSan runtime exists, and its instrumented entry crashes there.
#pragma once

#if defined(__SANITIZE_THREAD__)
#define CANDI_TARGET_CLONES_AVX2
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CANDI_TARGET_CLONES_AVX2
#endif
#endif

#ifndef CANDI_TARGET_CLONES_AVX2
#define CANDI_TARGET_CLONES_AVX2 __attribute__((target_clones("avx2", "default")))
#endif
