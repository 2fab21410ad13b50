/* A C math library that differs from the platform's in the last bit of
 * every result: each function is the platform's double-precision one,
 * rounded to float, then moved one step up. Preloaded into `weft`
 * (tests/portable.rs), it changes every result of a build whose simulation
 * calls the platform's single-precision functions, and none of one that
 * computes them itself (src/solver/portable.rs). Compile it with
 * -fno-builtin, or the compiler turns `(float)sin(x)` back into `sinf(x)`,
 * which is this file's own `sinf`. */
#include <math.h>
static float up(double v) { return nextafterf((float)v, INFINITY); }
float sinf(float x) { return up(sin(x)); }
float cosf(float x) { return up(cos(x)); }
void sincosf(float x, float *s, float *c) { *s = sinf(x); *c = cosf(x); }
float tanf(float x) { return up(tan(x)); }
float asinf(float x) { return up(asin(x)); }
float acosf(float x) { return up(acos(x)); }
float atanf(float x) { return up(atan(x)); }
float atan2f(float y, float x) { return up(atan2(y, x)); }
float expf(float x) { return up(exp(x)); }
float logf(float x) { return up(log(x)); }
float powf(float x, float y) { return up(pow(x, y)); }
float hypotf(float x, float y) { return up(hypot(x, y)); }
