#pragma once
// The frame rates the project accepts: --fps (every command that samples a motion) and the rate
// a BVH file states (Frame Time 1/kMaxFps .. 1/kMinFps s, avatar/bvh/bvh.cpp). 1000 Hz is above
// what motion capture delivers as BVH (inertial suits 60-240 Hz, optical systems 120-360 Hz at
// full resolution); a stated rate far beyond it is a wrong Frame Time, not a recording.
namespace embody {

inline constexpr double kMinFps = 1.0, kMaxFps = 1000.0;

}  // namespace embody
