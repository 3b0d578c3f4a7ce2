#pragma once
// The live mirror behind `embody mirror` (and the window `embody demo` opens): the same pipeline
// as `embody render --motion` (pose source -> One Euro filter + loss guard -> budgeted PIK on the
// IK thread -> triple buffer -> skinning palette -> render), drawn into a desktop window
// (engine/desktop_window.h) in real time. Keys: V first/third person, Space pause, R recenter (the
// motion's head as it is now becomes the origin, facing -Z, so the body faces the mirror), Esc quit.
#include <string>

#include "app/render_job.h"

namespace embody::app {

struct MirrorJob {
  RenderJob run;           // avatar, motion, spine, bone map, user height, profile, budget, size, view, fps, device
  int frames = 0;          // exit after this many frames shown (0: until the window closes)
  std::string screenshot;  // PNG of the window's last frame ("" none)
  bool loop = true;        // replay the motion from the start when it ends
  bool recenterAtStart = false;  // --recenter: the motion's first valid head becomes the origin, facing -Z
};

// True when a desktop display looks available (DISPLAY or WAYLAND_DISPLAY set): what `embody demo`
// checks before opening the mirror. Opening can still fail; runMirror then says why.
bool displayAvailable();

// Runs the window; prints errors as "error: ..." and returns the exit code (0, 1 runtime error
// such as no display, 2 bad option values).
int runMirror(const MirrorJob& job);

}  // namespace embody::app
