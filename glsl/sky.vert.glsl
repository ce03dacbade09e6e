#version 460
// Full-screen triangle from the vertex index; the fragment stage reconstructs view rays. Its
// edges lie outside the viewport on every side: lavapipe (Mesa 22.3) counts extra fragment
// invocations along a triangle edge that coincides with the viewport's edge.

layout(location = 0) out vec2 ndc;

void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2));
    ndc = p * 3.0 - 1.5;
    gl_Position = vec4(ndc, 0.0, 1.0);
}
