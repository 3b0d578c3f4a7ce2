#pragma once
// Human proportions every library uses alike (header only, no dependencies): the solver's eye
// point, calibration from an eye height, the trackers of synthetic motions and BVH clips.
namespace embody::avatar {

// Eye height over body height: H-Anim's 1.75 m humanoid has its eyes at 1.633 m.
inline constexpr double kEyeHeightRatio = 0.933;
// Eyes ahead of the head (neck) pivot over body height, head upright.
inline constexpr double kEyeForwardRatio = 0.045;
// Ankle joint centre above the sole over body height, standing (Drillis & Contini; Winter's
// segment table): 6.8 cm at 1.75 m.
inline constexpr double kAnkleHeightRatio = 0.039;

}  // namespace embody::avatar
