#pragma once
// "Render a frame of this avatar in this pose with this camera": the library-level entry point the
// CLI (`embody render`), the runtime's frame loop and the benchmarks share. Owns the renderer, the
// uploaded avatar and an offscreen target; computes globals and the palette per frame into
// reused buffers (no allocation per frame once sizes are known).
#include <array>
#include <memory>
#include <span>
#include <vector>

#include "avatar/avatar_asset.h"
#include "engine/camera.h"
#include "engine/offscreen_target.h"
#include "engine/overlay.h"
#include "engine/renderer.h"

namespace embody::engine {

enum class ViewKind { ThirdPerson, FirstPerson };
// Stereo pair: one multiview pass into a 2-layer image, or one pass per eye. On lavapipe both
// cost the same (docs/performance.md: 2x1440x1584 ~20 ms either way) and multiview mis-clips
// lines crossing the near plane in the second view (Mesa 22.3), so two passes is the default;
// it also serves OpenXR runtimes that hand out one swapchain per eye.
enum class StereoMode { Multiview, TwoPass };
constexpr StereoMode kDefaultStereoMode = StereoMode::TwoPass;

struct FrameOptions {
  ViewKind view = ViewKind::ThirdPerson;
  bool grid = true;
  bool skeleton = false;        // skeleton overlay, drawn on top
  std::vector<Gizmo> gizmos;    // tracking targets (head, hands)
  Lighting lighting;
  glm::vec4 clearColor{0.30f, 0.33f, 0.38f, 1.0f};
  // One per mesh.morphChannels (avatar::SecondaryMotion::morphWeights()); empty: the file's defaults.
  std::span<const float> morphWeights;
  // One per the asset's expressions.boundMaterials (avatar::SecondaryMotion::materialStates());
  // empty: the materials as loaded.
  std::span<const avatar::MaterialBindState> materialStates;
  double seconds = 0.0;  // the frame clock (SceneFrame::seconds)
};

struct AvatarRendererOptions {
  uint32_t width = 256, height = 256;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;  // 4 for 4x MSAA
  bool stereo = false;  // a 2-layer target for stereo pairs
  StereoMode stereoMode = kDefaultStereoMode;
};

// Joints the views and gizmos anchor to: from the asset's humanoid map when it has one, else by
// joint name ("head", "leftHand"/"hand_L", ...). -1 when not found.
struct AvatarAnchors {
  int head = -1, leftHand = -1, rightHand = -1;
  glm::vec3 forward{0.0f, 0.0f, 1.0f};  // the way the rest pose faces (glTF: +Z, VRM 0.x: -Z)
};
AvatarAnchors findAnchors(const avatar::AvatarAsset& asset);

// `asset` must outlive the AvatarRenderer (it is read for the skeleton and mesh every frame).
class AvatarRenderer {
 public:
  static Result<std::unique_ptr<AvatarRenderer>> create(const Device& device, const avatar::AvatarAsset& asset,
                                                        const AvatarRendererOptions& options = {});
  ~AvatarRenderer();

  // One frame, read back as RGBA8 (blocking).
  Result<avatar::Image> render(const avatar::SkeletonPose& pose, const Camera& camera, const FrameOptions& options);
  // A stereo pair (needs options.stereo), read back as two images (left, right).
  Result<std::array<avatar::Image, 2>> renderStereo(const avatar::SkeletonPose& pose, const std::array<Camera, 2>& eyes,
                                                   const FrameOptions& options);
  // Records and submits a frame without reading it back: what a frame costs on the device.
  // waitForCompletion=false keeps up to kFramesInFlight frames in flight.
  Status submitFrame(const avatar::SkeletonPose& pose, std::span<const Camera> cameras, const FrameOptions& options,
                     bool readback, bool waitForCompletion);

  // Globals and palette of `pose` (also what the last frame used).
  Status computePose(const avatar::SkeletonPose& pose);
  const std::vector<glm::mat4>& globals() const { return globals_; }
  const std::vector<glm::mat4>& palette() const { return palette_; }
  // The file's default morph weights (glTF mesh.weights), for frames without expressions.
  const std::vector<float>& defaultMorphWeights() const { return defaultMorphWeights_; }

  // An orbit camera that frames the avatar in `pose` (yaw/pitch in radians; yaw 0 = from the front).
  Camera orbitAround(const avatar::SkeletonPose& pose, float yaw = 0.5f, float pitch = 0.15f);
  // The eye pose for first-person views: between the eyes, facing the avatar's front, turned
  // with the head. Falls back to the top of the mesh when no head joint is found.
  glm::mat4 eyePose(const avatar::SkeletonPose& pose);
  // Gizmos at the head and hands (the tracking targets), from the posed skeleton.
  std::vector<Gizmo> trackingGizmos(const avatar::SkeletonPose& pose);

  const avatar::AvatarAsset& asset() const { return asset_; }
  Renderer& renderer() { return *renderer_; }
  const GpuAvatar& gpuAvatar() const { return *avatar_; }
  const OffscreenTarget& target() const { return target_; }
  const AvatarAnchors& anchors() const { return anchors_; }

 private:
  AvatarRenderer(const avatar::AvatarAsset& asset) : asset_(asset) {}
  const avatar::AvatarAsset& asset_;
  AvatarRendererOptions options_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<GpuAvatar> avatar_;
  OffscreenTarget target_;
  AvatarAnchors anchors_;
  std::vector<glm::mat4> globals_, restGlobals_, palette_;
  std::vector<float> defaultMorphWeights_;
  std::vector<glm::vec3> skinnedPositions_, skinnedNormals_;
  std::vector<LineVertex> lines_, overlay_;
  glm::vec3 eyeOffsetInHead_{0.0f};  // eye position in the head joint's rest frame
};

}  // namespace embody::engine
