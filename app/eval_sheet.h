#pragma once
// embody eval's contact sheet: the coupled run's kept poses rendered solid (the clip's own
// skeleton with its capsules), the clip's joints drawn over each as an orange ghost skeleton.
#include <filesystem>
#include <string>

#include "core/result.h"
#include "eval/clip_eval.h"
#include "tracking/bvh_avatar.h"

namespace embody::app {

Status writeEvalSheet(const tracking::BvhAvatar& avatar, const eval::ClipEval& e, const std::filesystem::path& file,
                      const std::string& device = "auto");

}  // namespace embody::app
