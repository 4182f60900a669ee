/* What any compiler must do with these sources, carried by the sources themselves.
 *
 * Included first by every translation unit of the binary: by rbfmu_core.h, and by the
 * generated model_funcs.c (fmu/build/codegen.py prepends the #include to CasADi's output), so that
 * `cc -shared -fPIC *.c` with no flags builds what the shipped binaries are (docs/importing.md
 * §Building from sources):
 * - only the fmi3* / fmi2* functions are exported: everything declared after this point is
 *   hidden, and the standard's headers mark their functions visibility("default"). Two FMUs
 *   loaded RTLD_GLOBAL into one process then never bind to each other's rb_* / model_*.
 *   The pragma also hides extern declarations, so every C library header any unit uses is
 *   included here, before it (a later #include of them is then a no-op).
 * - no floating-point contraction (a*b+c into an FMA): every platform rounds each operation
 *   alike, and results differ only where the platforms' libm do. gcc ignores the standard
 *   pragma and needs its optimize pragma; clang and others honour STDC FP_CONTRACT (clang's
 *   -ffp-contract=fast disregards pragmas by design: the one flag these sources cannot undo).
 * - value-changing options (-ffast-math, -Ofast) are refused. */
#ifndef RBFMU_BUILD_H
#define RBFMU_BUILD_H

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef __FAST_MATH__
#error "rbfmu: built with -ffast-math or -Ofast; the FMU needs IEEE arithmetic, drop that option"
#endif

#if defined(__GNUC__) && !defined(_WIN32) && !defined(__CYGWIN__)
#pragma GCC visibility push(hidden)
#endif

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("fp-contract=off")
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#else
#pragma STDC FP_CONTRACT OFF
#endif

#endif
