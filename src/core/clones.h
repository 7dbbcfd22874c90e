/*
 * clones.h - the hot kernels compiled for several x86-64 instruction sets in one portable build,
 * the best that the processor has chosen at load time (GCC's and Clang's target_clones: an ifunc
 * per function, resolved once by the dynamic loader from cpuid).
 *
 * The default build targets baseline x86-64 (SSE2, no FMA), so that its programs and the Docker
 * image run on any x86-64 processor; the kernels marked here also get an x86-64-v3 copy (AVX2,
 * FMA) and an x86-64-v4 copy (AVX-512). With -ffp-contract=fast (the Makefile's OPT) the copies
 * fuse multiply-adds as make bench's -march=native build does, so their rounding is that
 * build's, which the unit tests also pass. Mark functions that are called once per pass and
 * loop over the bodies inside (one indirect call per pass, nothing per body).
 * The figures: bench/NOTEBOOK.md, "The portable build (issue 26)".
 */
#ifndef CTC_CLONES_H
#define CTC_CLONES_H

/*
 * CTC_MULTIVERSION: on x86-64 (ELF), when the build's target lacks AVX2 (the portable default
 * build), the function is compiled for x86-64-v4, x86-64-v3 and the build's own target. Builds
 * for a target with AVX2 already (make bench's -march=native), other architectures, and
 * -DCTC_NO_CLONES (to measure the difference) get the one function.
 * CTC_SPECIALISE: the same, and every call inside the function inlined (GCC's flatten), so that
 * the kernels of dense.h and gdca_tree.h specialise on constant sizes, inside each copy for its
 * instruction set. Clang refuses flatten together with target_clones; there the copies alone,
 * and Clang's inliner takes the static inline kernels at -O1 and above.
 */
#if defined(__x86_64__) && defined(__ELF__) && !defined(__AVX2__) && !defined(CTC_NO_CLONES) &&    \
    defined(__has_attribute)
#if __has_attribute(target_clones)
#define CTC_MULTIVERSION                                                                           \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
#endif
#ifdef CTC_MULTIVERSION
#ifdef __clang__
#define CTC_SPECIALISE CTC_MULTIVERSION
#else
#define CTC_SPECIALISE __attribute__((flatten)) CTC_MULTIVERSION
#endif
#else
#define CTC_MULTIVERSION
#define CTC_SPECIALISE __attribute__((flatten))
#endif

#endif
