/* rk_fp.h -- the floating-point contract of every C source of the engine and the FMI layer, pinned by the
 * sources themselves: no contraction of a * b + c into a fused multiply-add, whatever flags the build passes.
 *
 * Included FIRST by every .c file (before any other header, so that it precedes every function definition of
 * the translation unit). Why: the engine is written as the Python computes (one rounding per operation); a
 * compiler that fuses multiply-adds (GCC's default outside ISO C mode -- gnu99/gnu17, what CMake and fmpy's
 * `compile` use -- on aarch64, or on x86-64 with -march=haswell and later; clang's default within an
 * expression) moves the results by round-off that impacts amplify (5e-11 rad on the flexible oscillator).
 * The FMUs' own binaries are also built with -ffp-contract=off; these pragmas make an importer's build of
 * sources/ give the same bits with its own flags (tests/test_cross_platform.py checks an aarch64 build
 * without the flag for fmadd/fmsub instructions).
 *
 *   clang (and clang-based compilers: Apple clang, icx, armclang): the C99 pragma and clang's own;
 *   GCC: it ignores the C99 pragma, so the optimize pragma (-ffp-contract=off for every function that
 *        follows; allowed as an optimization option since GCC 4.4);
 *   MSVC: its fp_contract pragma (contraction is off under /fp:precise anyway, the default);
 *   any other C99 compiler: the standard pragma. */
#ifndef RK_FP_H
#define RK_FP_H

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#pragma clang fp contract(off)
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#else
#pragma STDC FP_CONTRACT OFF
#endif

#endif /* RK_FP_H */
