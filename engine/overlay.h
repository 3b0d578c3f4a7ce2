#pragma once
// Line geometry for the debug overlays: tracking-target gizmos (head, hands) and the skeleton.
#include <glm/glm.hpp>
#include <vector>

#include "avatar/skeleton.h"
#include "engine/renderer.h"

namespace embody::engine {

struct Gizmo {
  glm::mat4 pose{1.0f};               // world pose of the tracked target (rotation + position)
  glm::vec4 color{1.0f, 0.8f, 0.1f, 1.0f};
  float size = 0.08f;                 // metres, half-extent of the marker
};

// An RGB axis tripod (the target's orientation) inside a coloured octahedron (its position).
void appendGizmo(std::vector<LineVertex>& lines, const Gizmo& gizmo);
// One line from every joint to its parent, at the posed global positions.
void appendSkeleton(std::vector<LineVertex>& lines, const avatar::Skeleton& skeleton,
                    const std::vector<glm::mat4>& globals, const glm::vec4& color = {1.0f, 0.9f, 0.2f, 1.0f});

}  // namespace embody::engine
