#ifndef LAMINA_LIB_MATH
#define LAMINA_LIB_MATH

const float PI = 3.14159265358979323846;
const float TWO_PI = 6.28318530717958647692;
const float INV_PI = 0.31830988618379067154;

float saturate(float x) { return clamp(x, 0.0, 1.0); }

float pow5(float x) {
    float x2 = x * x;
    return x2 * x2 * x;
}

#endif
