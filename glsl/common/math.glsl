#ifndef MATH_GLSL
#define MATH_GLSL
const float PI = 3.14159265358979;
#endif
