#include "avatar/vrm/secondary_motion.h"

namespace embody::avatar {

SecondaryMotion::SecondaryMotion(const AvatarAsset& asset, const SecondaryMotionOptions& options)
    : asset_(asset), options_(options), blinkSchedule_(options.blinkSeed) {
  const size_t n = asset.expressions.expressions.size();
  manual_.assign(n, 0.0f);
  weights_.assign(n, 0.0f);
  effective_.assign(n, 0.0f);
  defaults_ = defaultMorphWeights(asset.mesh);
  morph_ = defaults_;
  for (int m : asset.expressions.boundMaterials)  // (a hand-built set naming no material: the job refuses it)
    materialStates_.push_back(m >= 0 && static_cast<size_t>(m) < asset.materials.size()
                                  ? materialBindBase(asset.materials[static_cast<size_t>(m)])
                                  : MaterialBindState{});
  globals_.resize(asset.skeleton.joints.size());
  springState_.resize(asset.springBones, asset.skeleton.joints.size());
  job_.setup = &asset.springBones;
  job_.skeleton = &asset.skeleton;
  job_.state = &springState_;
  job_.stepSeconds = options.springStepSeconds;
  const int hips = asset.humanoid.joint(HumanBone::hips);
  job_.rootJoint = hips >= 0 ? hips : 0;
}

void SecondaryMotion::update(SkeletonPose& pose, double dt, const std::optional<glm::vec3>& lookTarget) {
  if (pose.local.size() != asset_.skeleton.joints.size()) return;
  if (!(dt >= 0.0) || !std::isfinite(dt)) dt = 0.0;
  seconds_ += dt;
  std::copy(manual_.begin(), manual_.end(), weights_.begin());
  computeGlobals(asset_.skeleton, pose, globals_);
  // Look-at first: its eye rotations are part of the pose the springs see.
  gaze_ = {};
  if (options_.lookAt && lookTarget && asset_.lookAt.type != LookAtSetup::Type::None) {
    gaze_ = gazeTowards(asset_.lookAt, asset_.skeleton, globals_, *lookTarget);
    applyGaze(asset_.lookAt, asset_.skeleton, globals_, gaze_, pose, asset_.expressions, weights_);
  }
  blink_ = options_.blink ? blinkSchedule_.advance(dt) : 0.0f;
  if (const int b = asset_.expressions.find(ExpressionPreset::Blink); b >= 0 && blink_ > 0.0f)
    weights_[static_cast<size_t>(b)] = std::max(weights_[static_cast<size_t>(b)], blink_);
  ExpressionEvaluateJob ej;
  ej.set = &asset_.expressions;
  ej.defaultMorphWeights = defaults_;
  ej.weights = weights_;
  ej.effectiveWeights = effective_;
  ej.morphWeights = morph_;
  ej.Run();
  MaterialBindEvaluateJob mj;
  mj.set = &asset_.expressions;
  mj.materials = asset_.materials;
  mj.effectiveWeights = effective_;
  mj.states = materialStates_;
  mj.Run();
  if (options_.springBones && !asset_.springBones.empty()) {
    if (asset_.lookAt.type == LookAtSetup::Type::Bone) computeGlobals(asset_.skeleton, pose, globals_);
    job_.pose = &pose;
    job_.globals = globals_;
    job_.deltaTime = dt;
    job_.reset = resetSprings_;
    resetSprings_ = false;
    job_.Run();
  }
}

}  // namespace embody::avatar
