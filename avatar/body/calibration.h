#pragma once
// Calibration: scaling the body to the user, and the small JSON profile that remembers it.
//
// The avatar is scaled uniformly so that its height matches the user's: from --user-height, or
// from the eye height (the head pose at calibration; an HMD knows the eyes, not the top of the
// head). Eye height is taken as 0.933 of body height (H-Anim's 1.75 m humanoid has its eyes at
// about 1.633 m), for the avatar too unless it states an eye position. Arm span is optional: the
// avatar's limbs are not rescaled (non-uniform limb scaling would break the exact pivot match with
// the render skeleton); instead the runtime places the hands relative to the shoulders by the arm
// length ratio (armLengthScale, runtime/tracker_targets_job.h).
#include <optional>
#include <string>
#include <string_view>

#include "avatar/avatar_asset.h"
#include "avatar/body/anthropometry.h"  // kEyeHeightRatio
#include "core/result.h"

namespace embody::avatar {

// The body heights (and arm spans) calibration, profiles and every CLI option accept, in metres.
constexpr double kMinBodyHeight = 0.5, kMaxBodyHeight = 2.6;
bool plausibleBodyHeight(double metres);  // finite and within [kMinBodyHeight, kMaxBodyHeight]
std::string bodyHeightRange();            // "0.5 .. 2.6 m", for help texts and messages
// The arm-length ratios (BodyProfile::armLengthScale) the runtime applies: the user's arms at
// least half and at most twice the avatar's, scaled to the user's height.
constexpr double kMinArmScale = 0.5, kMaxArmScale = 2.0;
bool plausibleArmScale(double ratio);  // finite and within [kMinArmScale, kMaxArmScale]

struct CalibrationInput {
  std::optional<double> userHeight;  // metres, total height
  std::optional<double> eyeHeight;   // metres, eyes above the floor (used when no user height)
  std::optional<double> armSpan;     // metres, fingertip to fingertip
};

struct BodyProfile {
  std::string avatar;          // source path or "default"
  double userHeight = 0.0;     // metres
  double eyeHeight = 0.0;      // metres
  double armSpan = 0.0;        // metres, 0 when not measured
  double avatarHeight = 0.0;   // metres, at the avatar's own scale
  double avatarArmSpan = 0.0;  // metres, hand joint to hand joint along the arm chains + hands
  double scale = 1.0;          // user / avatar, applied uniformly
  double armScale = 1.0;       // user arm span / avatar arm span (stored, not applied)
  // The user's arm (shoulder to wrist) over the avatar's scaled to the user's height: a span that
  // differs from the avatar's (scaled) differs in the two arms, the shoulders and hands scale with
  // height. What the runtime applies (runtime::AvatarBodyOptions::armScale). Not stored: computed
  // by calibrate() for the avatar at hand.
  double armLengthScale = 1.0;
};

// Height of the avatar standing at rest: mesh bounds along up when it has a mesh, else from the
// head joint (head joint / 0.91).
double avatarHeight(const AvatarAsset& avatar);

// The standing heights an avatar may have, in metres: a tenth of a default (1.75 m) person to a
// giant of 10 m, so 0.3x to 3x scaled avatars work. Outside, the file is in other units than
// metres (175 m: centimetres without a root scale; 1.75 cm: the reverse) or has nothing to measure.
constexpr double kMinAvatarHeight = 0.25, kMaxAvatarHeight = 10.0;
// avatarHeight(avatar) when it is finite and within [kMinAvatarHeight, kMaxAvatarHeight] (a mesh
// under that on a skeleton that is not, such as a floating head, gives the skeleton's head-joint
// height); else an error with the measured height and the likely unit mistake. The one check `avatar calibrate` and
// every body built from an avatar (runtime::AvatarBodySolver::create) make.
Result<double> measureAvatarHeight(const AvatarAsset& avatar);

// Needs a usable humanoid mapping for the arm span; fails on non-positive or absurd inputs
// (outside 0.5 - 2.6 m) and when neither height is given.
Result<BodyProfile> calibrate(const AvatarAsset& avatar, const CalibrationInput& input);

Status saveProfile(const BodyProfile& profile, const std::string& path);
Result<BodyProfile> loadProfile(const std::string& path);  // validates every number
// The same from the file's text; `path` only names it in errors.
Result<BodyProfile> parseProfile(std::string_view text, const std::string& path);

}  // namespace embody::avatar
