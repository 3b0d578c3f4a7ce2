#include "engine/overlay.h"

namespace embody::engine {

void appendGizmo(std::vector<LineVertex>& lines, const Gizmo& g) {
  const glm::vec3 o(g.pose[3]);
  const glm::vec3 axes[3] = {glm::normalize(glm::vec3(g.pose[0])), glm::normalize(glm::vec3(g.pose[1])),
                             glm::normalize(glm::vec3(g.pose[2]))};
  const glm::vec4 axisColor[3] = {{1.0f, 0.15f, 0.15f, 1.0f}, {0.15f, 1.0f, 0.15f, 1.0f}, {0.2f, 0.4f, 1.0f, 1.0f}};
  for (int i = 0; i < 3; ++i) {
    lines.push_back({o, axisColor[i]});
    lines.push_back({o + axes[i] * (g.size * 1.5f), axisColor[i]});
  }
  // Octahedron: the six tips along the target's axes, twelve edges.
  glm::vec3 tips[6];
  for (int i = 0; i < 3; ++i) {
    tips[2 * i] = o + axes[i] * g.size;
    tips[2 * i + 1] = o - axes[i] * g.size;
  }
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      for (int sa = 0; sa < 2; ++sa)
        for (int sb = 0; sb < 2; ++sb) {
          lines.push_back({tips[2 * a + sa], g.color});
          lines.push_back({tips[2 * b + sb], g.color});
        }
}

void appendSkeleton(std::vector<LineVertex>& lines, const avatar::Skeleton& skeleton,
                    const std::vector<glm::mat4>& globals, const glm::vec4& color) {
  for (size_t j = 0; j < skeleton.joints.size() && j < globals.size(); ++j) {
    const int p = skeleton.joints[j].parent;
    if (p < 0) continue;
    lines.push_back({glm::vec3(globals[p][3]), color});
    lines.push_back({glm::vec3(globals[j][3]), color});
  }
}

}  // namespace embody::engine
