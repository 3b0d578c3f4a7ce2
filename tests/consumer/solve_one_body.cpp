// Solves one body with the installed Embody: the default avatar follows one second of the
// figure-eight motion (head + hands tracked) through the runtime's synchronous body
// (filter -> guard -> budgeted PIK -> retarget). Exit 0 when every frame was solved, the pose is
// finite and the hands reach their targets; otherwise one line saying what failed.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "avatar/procedural/default_avatar.h"
#include "runtime/tracked_avatar_body.h"
#include "tracking/pose_source.h"

int main() {
  using namespace embody;
  const avatar::AvatarAsset asset = avatar::buildDefaultAvatar();
  runtime::TrackedBodyOptions options;
  options.body.userHeight = 1.75f;
  options.stage.budgetSeconds = 0.05;  // generous: this checks the package, not the timing
  auto body = runtime::TrackedAvatarBody::create(asset, options);
  auto source = tracking::openPoseSource("synthetic:figure8", {.userHeight = 1.75f});
  if (!body || !source) {
    std::fprintf(stderr, "error: %s\n", !body ? body.error().c_str() : source.error().c_str());
    return 1;
  }
  avatar::SkeletonPose pose;
  float worstHand = 0.0f;
  const int frames = 90;
  for (int i = 0; i < frames; ++i) {
    if (!(*body)->solve((*source)->sample(i / 90.0), pose)) {
      std::fprintf(stderr, "error: frame %d not solved\n", i);
      return 1;
    }
    for (const auto& local : pose.local)
      if (!std::isfinite(local.translation.x + local.translation.y + local.translation.z + local.rotation.w)) {
        std::fprintf(stderr, "error: frame %d has a non-finite joint\n", i);
        return 1;
      }
    if (i >= frames / 2) {  // after the first half second, the warm-started solve has converged
      const auto& residual = (*body)->frame().stats.residual;
      for (tracking::TrackerId hand : {tracking::TrackerId::LeftHand, tracking::TrackerId::RightHand})
        worstHand = std::max(worstHand, residual[static_cast<size_t>(hand)]);
    }
  }
  std::printf("solved %d frames, worst hand residual %.1f mm\n", frames, worstHand * 1e3f);
  if (!(worstHand >= 0.0f && worstHand < 0.03f)) {
    std::fprintf(stderr, "error: hand residual %.1f mm, expected under 30 mm\n", worstHand * 1e3f);
    return 1;
  }
  return 0;
}
