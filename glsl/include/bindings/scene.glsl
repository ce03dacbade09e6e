// Set 1 of the scene's graphics passes (forward, sky): the frame constants and the
// prefiltered environment. Mirrors SCENE_BINDINGS in src/render/renderer.rs.
#ifndef LAMINA_BINDINGS_SCENE
#define LAMINA_BINDINGS_SCENE

#include "../shared/frame.glsl"

layout(set = 1, binding = 0, std140) uniform Frame {
    FrameConstants frame;
};
layout(set = 1, binding = 1) uniform samplerCube prefiltered;

#endif
