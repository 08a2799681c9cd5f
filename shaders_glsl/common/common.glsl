// Shared by every vista shader. Host twins of constants live next to the
// code that uses them, each with a comment pointing here.
#ifndef VISTA_COMMON_GLSL
#define VISTA_COMMON_GLSL

// A NaN produced at run time from bits the host passes in: a NaN literal is
// folded by compilers and rejected by naga's validator.
float runtime_nan(uint nan_bits) { return uintBitsToFloat(nan_bits); }

#endif
