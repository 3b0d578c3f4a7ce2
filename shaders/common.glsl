// Shared by every graphics shader: the per-frame scene block (views, light), the push constant
// and the view index. Included with GL_GOOGLE_include_directive; not compiled on its own.
#extension GL_EXT_multiview : require

const uint kMaxViews = 8u;

struct ViewData {
  mat4 viewProj;
  vec4 eye;  // world-space camera position
};

layout(set = 0, binding = 0, std140) uniform Scene {
  ViewData views[kMaxViews];
  vec4 lightDirection;  // xyz: unit vector towards the light
  vec4 lightColor;      // rgb: linear radiance of the directional light
  vec4 skyColor;        // hemisphere ambient from above
  vec4 groundColor;     // hemisphere ambient from below
  vec4 clock;           // x: seconds of the frame clock (MToon UV animation)
} scene;

layout(push_constant) uniform Push {
  uint viewBase;  // first view of this pass; gl_ViewIndex adds 0 or 1 under multiview
  float aspect;   // the target's width / height (screen-space outline widths)
} pc;

uint viewIndex() { return pc.viewBase + gl_ViewIndex; }
