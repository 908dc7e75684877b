/* Test harness only, never shipped: the C99 complex functions of the Windows Universal C Runtime that Debian 12's
 * Wine 8.0 leaves unimplemented in its ucrtbase.dll (76 stubs; calling one stops the process with "Unimplemented
 * function ucrtbase.dll.crealf"). numpy 2.x, which the Windows Python 3.13 tests and Windows `bpy` 5.2 need, imports
 * them. tests/windows/wine_shims.py builds this into a native ucrtbase.dll that exports these and forwards every other
 * export to a renamed copy of Wine's own ucrtbase (see docs/development.md, "What Wine cannot run").
 *
 * MSVC's calling convention for <complex.h>: _Dcomplex {double[2]} (16 bytes) is passed by reference and returned
 * through a hidden pointer, _Fcomplex {float[2]} (8 bytes) in a general register; MSVC's long double is a double, so
 * _Lcomplex is _Dcomplex. mingw-w64's gcc follows the same rules for these structs, so plain C structs match; the
 * maths is mingw-w64's C99 complex library (libmingwex). Each function is named shim_<name>; the .def file maps the
 * exported names onto them (the C names would clash with <complex.h>). */
#include <complex.h>
#include <math.h>

typedef struct { double re, im; } Dcomplex;
typedef struct { float re, im; } Fcomplex;

static double complex to_c(Dcomplex z) { return __builtin_complex(z.re, z.im); }
static float complex to_cf(Fcomplex z) { return __builtin_complex(z.re, z.im); }
static Dcomplex from_c(double complex z) { Dcomplex result = {creal(z), cimag(z)}; return result; }
static Fcomplex from_cf(float complex z) { Fcomplex result = {crealf(z), cimagf(z)}; return result; }

/* name(z) -> complex, in the double (also the long double) and float forms. */
#define UNARY(name)                                                                   \
  Dcomplex shim_##name(Dcomplex z) { return from_c(name(to_c(z))); }                  \
  Dcomplex shim_##name##l(Dcomplex z) { return from_c(name(to_c(z))); }               \
  Fcomplex shim_##name##f(Fcomplex z) { return from_cf(name##f(to_cf(z))); }
UNARY(cacos) UNARY(cacosh) UNARY(casin) UNARY(casinh) UNARY(catan) UNARY(catanh) UNARY(ccos) UNARY(ccosh)
UNARY(cexp) UNARY(clog) UNARY(conj) UNARY(cproj) UNARY(csin) UNARY(csinh) UNARY(csqrt) UNARY(ctan) UNARY(ctanh)

/* name(z) -> real. */
#define TO_REAL(name, expression_d, expression_f)                                     \
  double shim_##name(Dcomplex z) { return expression_d; }                             \
  double shim_##name##l(Dcomplex z) { return expression_d; }                          \
  float shim_##name##f(Fcomplex z) { return expression_f; }
TO_REAL(cabs, hypot(z.re, z.im), hypotf(z.re, z.im))
TO_REAL(carg, atan2(z.im, z.re), atan2f(z.im, z.re))
TO_REAL(creal, z.re, z.re)
TO_REAL(cimag, z.im, z.im)
TO_REAL(norm, z.re * z.re + z.im * z.im, z.re * z.re + z.im * z.im) /* MSVC's norm is |z|^2 */

/* log10 of a complex number: log(z) / log(10). */
Dcomplex shim_clog10(Dcomplex z) { return from_c(clog(to_c(z)) / M_LN10); }
Dcomplex shim_clog10l(Dcomplex z) { return shim_clog10(z); }
Fcomplex shim_clog10f(Fcomplex z) { return from_cf(clogf(to_cf(z)) / (float)M_LN10); }

Dcomplex shim_cpow(Dcomplex x, Dcomplex y) { return from_c(cpow(to_c(x), to_c(y))); }
Dcomplex shim_cpowl(Dcomplex x, Dcomplex y) { return shim_cpow(x, y); }
Fcomplex shim_cpowf(Fcomplex x, Fcomplex y) { return from_cf(cpowf(to_cf(x), to_cf(y))); }

/* MSVC's C has no complex operators: it builds and multiplies complex numbers with these. */
Dcomplex shim__Cbuild(double re, double im) { Dcomplex result = {re, im}; return result; }
Dcomplex shim__LCbuild(double re, double im) { return shim__Cbuild(re, im); }
Fcomplex shim__FCbuild(float re, float im) { Fcomplex result = {re, im}; return result; }
Dcomplex shim__Cmulcc(Dcomplex x, Dcomplex y) { return from_c(to_c(x) * to_c(y)); }
Dcomplex shim__LCmulcc(Dcomplex x, Dcomplex y) { return shim__Cmulcc(x, y); }
Fcomplex shim__FCmulcc(Fcomplex x, Fcomplex y) { return from_cf(to_cf(x) * to_cf(y)); }
Dcomplex shim__Cmulcr(Dcomplex x, double y) { Dcomplex result = {x.re * y, x.im * y}; return result; }
Dcomplex shim__LCmulcr(Dcomplex x, double y) { return shim__Cmulcr(x, y); }
Fcomplex shim__FCmulcr(Fcomplex x, float y) { Fcomplex result = {x.re * y, x.im * y}; return result; }
