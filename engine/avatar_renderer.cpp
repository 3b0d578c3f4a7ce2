#include "engine/avatar_renderer.h"

#include <algorithm>
#include <cctype>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "avatar/body/eye_point.h"

namespace embody::engine {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// Best joint whose lower-cased name contains `key` and, for hands, a side marker; shorter names
// win ("head" over "headtop_end"), and names with "end"/"top" (leaf helpers) lose.
int findByName(const avatar::Skeleton& s, const std::string& key, int side) {
  int best = -1;
  size_t bestScore = SIZE_MAX;
  for (size_t i = 0; i < s.joints.size(); ++i) {
    const std::string n = lower(s.joints[i].name);
    if (n.find(key) == std::string::npos) continue;
    if (side != 0) {
      const bool left = n.find("left") != std::string::npos || n.find("_l") != std::string::npos ||
                        n.find(".l") != std::string::npos || n.rfind("l_", 0) == 0;
      const bool right = n.find("right") != std::string::npos || n.find("_r") != std::string::npos ||
                         n.find(".r") != std::string::npos || n.rfind("r_", 0) == 0;
      if ((side < 0 && !left) || (side > 0 && !right)) continue;
    }
    size_t score = n.size() + ((n.find("end") != std::string::npos || n.find("top") != std::string::npos) ? 100 : 0);
    if (score < bestScore) {
      bestScore = score;
      best = int(i);
    }
  }
  return best;
}

glm::mat3 rotationOf(const glm::mat4& m) {
  return glm::mat3(glm::normalize(glm::vec3(m[0])), glm::normalize(glm::vec3(m[1])), glm::normalize(glm::vec3(m[2])));
}

}  // namespace

AvatarAnchors findAnchors(const avatar::AvatarAsset& asset) {
  AvatarAnchors a;
  const auto& h = asset.humanoid;
  if (h.method != avatar::MappingMethod::None) {
    a.head = h.joint(avatar::HumanBone::head);
    a.leftHand = h.joint(avatar::HumanBone::leftHand);
    a.rightHand = h.joint(avatar::HumanBone::rightHand);
    if (glm::length(h.forward) > 0.5f) a.forward = glm::normalize(h.forward);
    if (a.head >= 0) return a;
  }
  const auto& skeleton = asset.skeleton;
  a.head = findByName(skeleton, "head", 0);
  a.leftHand = findByName(skeleton, "hand", -1);
  a.rightHand = findByName(skeleton, "hand", +1);
  if (a.leftHand < 0) a.leftHand = findByName(skeleton, "wrist", -1);
  if (a.rightHand < 0) a.rightHand = findByName(skeleton, "wrist", +1);
  return a;
}

Result<std::unique_ptr<AvatarRenderer>> AvatarRenderer::create(const Device& device, const avatar::AvatarAsset& asset,
                                                               const AvatarRendererOptions& options) {
  std::unique_ptr<AvatarRenderer> r(new AvatarRenderer(asset));
  r->options_ = options;
  auto renderer = Renderer::create(device);
  if (!renderer) return Error{renderer.error()};
  r->renderer_ = std::move(renderer).value();
  auto gpu = r->renderer_->upload(asset);
  if (!gpu) return Error{gpu.error()};
  r->avatar_ = std::move(gpu).value();
  OffscreenDesc desc;
  desc.width = options.width;
  desc.height = options.height;
  desc.layers = options.stereo ? 2 : 1;
  desc.samples = options.samples;
  auto target = OffscreenTarget::create(device, desc);
  if (!target) return Error{target.error()};
  r->target_ = std::move(target).value();
  r->anchors_ = findAnchors(asset);
  r->defaultMorphWeights_ = avatar::defaultMorphWeights(asset.mesh);

  // The eye point the body solver uses too (avatar/body/eye_point.h), kept in the head joint's
  // rest frame so that it turns with the head.
  avatar::computeGlobals(asset.skeleton, avatar::SkeletonPose::rest(asset.skeleton), r->restGlobals_);
  const int head = r->anchors_.head;
  if (head >= 0) {
    const glm::vec3 eye(avatar::restEyePoint(asset, head, r->anchors_.forward).position);
    r->eyeOffsetInHead_ = glm::vec3(glm::inverse(r->restGlobals_[head]) * glm::vec4(eye, 1.0f));
  }
  if (auto s = r->computePose(avatar::SkeletonPose::rest(asset.skeleton)); !s) return Error{s.error()};
  return r;
}

AvatarRenderer::~AvatarRenderer() {
  if (renderer_) renderer_->waitIdle();
}

Status AvatarRenderer::computePose(const avatar::SkeletonPose& pose) {
  if (pose.local.size() != asset_.skeleton.joints.size())
    return Error{"the pose has " + std::to_string(pose.local.size()) + " joints; the skeleton has " +
                 std::to_string(asset_.skeleton.joints.size())};
  avatar::computeGlobals(asset_.skeleton, pose, globals_);
  for (const auto& g : globals_)
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k)
        if (!std::isfinite(g[c][k])) return Error{"the pose has non-finite transforms (NaN or infinity)"};
  avatar::computeSkinningPalette(asset_, globals_, palette_);
  return {};
}

Camera AvatarRenderer::orbitAround(const avatar::SkeletonPose& pose, float yaw, float pitch) {
  const float aspect = float(options_.width) / float(options_.height);
  const FovAngles fov = FovAngles::symmetric(glm::radians(40.0f), aspect);
  Bounds b;
  if (computePose(pose)) {
    avatar::skinOnCpu(asset_.mesh, palette_, skinnedPositions_, skinnedNormals_);
    b = boundsOf(skinnedPositions_);
  }
  if (b.empty()) b.add(glm::vec3(-0.5f, 0.0f, -0.5f)), b.add(glm::vec3(0.5f, 1.8f, 0.5f));
  // Yaw 0 is the avatar's front, whichever way its file faces (orbitCamera's 0 is from +Z, the
  // glTF front): a VRM 0.x avatar (facing -Z) or one facing +X was otherwise shown from behind or
  // in profile.
  const float front = std::atan2(anchors_.forward.x, anchors_.forward.z);
  return orbitCamera(b.center(), framingDistance(b.radius(), fov), yaw + front, pitch, fov, 0.05f, 100.0f);
}

glm::mat4 AvatarRenderer::eyePose(const avatar::SkeletonPose& pose) {
  // Camera axes for looking along the avatar's forward: -Z = forward, +Y = up, +X = right.
  const glm::vec3 f = anchors_.forward, up(0.0f, 1.0f, 0.0f);
  glm::mat4 faceFront(1.0f);
  faceFront[0] = glm::vec4(glm::normalize(glm::cross(f, up)), 0.0f);
  faceFront[1] = glm::vec4(up, 0.0f);
  faceFront[2] = glm::vec4(-f, 0.0f);
  if (!computePose(pose)) return faceFront;
  const int head = anchors_.head;
  if (head < 0) {
    avatar::skinOnCpu(asset_.mesh, palette_, skinnedPositions_, skinnedNormals_);
    const Bounds b = boundsOf(skinnedPositions_);
    const glm::vec3 eye = b.empty() ? glm::vec3(0.0f, 1.6f, 0.0f) : glm::vec3(b.center().x, b.max.y, b.center().z);
    return glm::translate(glm::mat4(1.0f), eye) * faceFront;
  }
  const glm::mat4& g = globals_[head];
  const glm::vec3 eye(g * glm::vec4(eyeOffsetInHead_, 1.0f));
  const glm::mat3 turn = rotationOf(g) * glm::transpose(rotationOf(restGlobals_[head]));
  glm::mat4 m = glm::mat4(turn) * faceFront;
  m[3] = glm::vec4(eye, 1.0f);
  return m;
}

std::vector<Gizmo> AvatarRenderer::trackingGizmos(const avatar::SkeletonPose& pose) {
  std::vector<Gizmo> out;
  if (!computePose(pose)) return out;
  const int joints[3] = {anchors_.head, anchors_.leftHand, anchors_.rightHand};
  const glm::vec4 colors[3] = {{1.0f, 0.85f, 0.1f, 1.0f}, {0.1f, 0.9f, 1.0f, 1.0f}, {1.0f, 0.3f, 0.9f, 1.0f}};
  for (int i = 0; i < 3; ++i) {
    if (joints[i] < 0) continue;
    Gizmo g;
    g.pose = glm::mat4(rotationOf(globals_[joints[i]]));
    g.pose[3] = globals_[joints[i]][3];
    g.color = colors[i];
    out.push_back(g);
  }
  return out;
}

Status AvatarRenderer::submitFrame(const avatar::SkeletonPose& pose, std::span<const Camera> cameras,
                                   const FrameOptions& options, bool readback, bool waitForCompletion) {
  if (auto s = computePose(pose); !s) return s;
  lines_.clear();
  overlay_.clear();
  for (const auto& g : options.gizmos) appendGizmo(lines_, g);
  if (options.skeleton) appendSkeleton(overlay_, asset_.skeleton, globals_);

  Renderer& r = *renderer_;
  if (auto s = r.beginFrame(); !s) return s;
  SceneFrame scene;
  scene.avatar = avatar_.get();
  scene.palette = palette_;
  scene.morphWeights = options.morphWeights.empty() ? std::span<const float>(defaultMorphWeights_) : options.morphWeights;
  scene.materialStates = options.materialStates;
  scene.seconds = options.seconds;
  scene.firstPerson = options.view == ViewKind::FirstPerson;
  scene.grid = options.grid;
  scene.lines = lines_;
  scene.overlayLines = overlay_;
  scene.lighting = options.lighting;
  Status s = r.setScene(scene);
  if (s && cameras.size() == 2) {
    if (!options_.stereo) s = Error{"stereo frames need AvatarRendererOptions::stereo"};
    else if (options_.stereoMode == StereoMode::Multiview) {
      PassTarget t = target_.allLayers();
      t.clearColor = options.clearColor;
      s = r.drawPass(cameras, t);
    } else {
      for (uint32_t eye = 0; eye < 2 && s; ++eye) {
        PassTarget t = target_.layer(eye);
        t.clearColor = options.clearColor;
        s = r.drawPass(cameras.subspan(eye, 1), t);
      }
    }
  } else if (s && cameras.size() == 1) {
    PassTarget t = options_.stereo ? target_.layer(0) : target_.allLayers();
    t.clearColor = options.clearColor;
    s = r.drawPass(cameras, t);
  } else if (s) {
    s = Error{"a frame takes one camera or a stereo pair"};
  }
  if (s && readback) target_.recordReadback(r.commandBuffer(), 0, cameras.size() == 2 ? 2 : 1);
  SubmitSync sync;
  sync.waitForCompletion = waitForCompletion || readback;
  // Always submit an opened frame, even after an error, so the frame slot stays consistent.
  Status submitted = r.endFrame(sync);
  if (!s) return s;
  return submitted;
}

Result<avatar::Image> AvatarRenderer::render(const avatar::SkeletonPose& pose, const Camera& camera,
                                             const FrameOptions& options) {
  if (auto s = submitFrame(pose, std::span<const Camera>(&camera, 1), options, true, true); !s) return Error{s.error()};
  return target_.pixels(0);
}

Result<std::array<avatar::Image, 2>> AvatarRenderer::renderStereo(const avatar::SkeletonPose& pose,
                                                                 const std::array<Camera, 2>& eyes,
                                                                 const FrameOptions& options) {
  if (auto s = submitFrame(pose, eyes, options, true, true); !s) return Error{s.error()};
  return std::array<avatar::Image, 2>{target_.pixels(0), target_.pixels(1)};
}

}  // namespace embody::engine
