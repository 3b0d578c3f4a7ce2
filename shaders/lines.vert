#version 460
// Ground grid, tracking-target gizmos and the skeleton overlay: coloured world-space lines.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec4 inColor;
layout(location = 0) out vec4 outColor;

void main() {
  outColor = inColor;
  gl_Position = scene.views[viewIndex()].viewProj * vec4(inPosition, 1.0);
}
