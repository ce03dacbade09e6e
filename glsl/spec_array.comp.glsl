#version 460
// Checks that a function-local array sized by the MAX_LAYERS specialization constant really
// has that size on the device: writes its length and the sum 1 + 2 + … + length.
#include "shared/variant.glsl"

layout(local_size_x_id = SHADE_LOCAL_SIZE_X_ID) in;

layout(set = 0, binding = 0, std430) writeonly buffer Result {
    uint length_and_sum[2];
} result;

void main() {
    float layers[MAX_LAYERS];
    for (int i = 0; i < layers.length(); ++i) {
        layers[i] = float(i + 1);
    }
    float sum = 0.0;
    for (int i = 0; i < layers.length(); ++i) {
        sum += layers[i];
    }
    result.length_and_sum[0] = uint(layers.length());
    result.length_and_sum[1] = uint(sum);
}
