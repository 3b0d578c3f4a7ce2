#pragma once
// Small, fully specified models for tests, benchmarks and demos. They are not the avatar body
// model (avatar/) or the anatomical coupled spine (ik/spine/): just stable fixtures.
#include "ik/model.h"
#include "core/result.h"

namespace embody::test {

// A 61-dof humanoid, y up, z forward, x to the character's left, 1.75 m tall: free root at the
// hips; lumbar/thorax/chest/neck/head ball joints; per arm clavicle (swing), shoulder (ball),
// elbow + forearm twist (revolute), wrist (swing); per leg hip (ball), knee (revolute), ankle
// (ball), toes (revolute); fixed end sites. Anatomical-ish limits and de Leva-like segment
// masses (75 kg). Six tasks on four levels, the PIK benchmark set (32 rows):
//   level 0: "left_foot", "right_foot" (pose);  level 1: "com" (centre of mass on the ground);
//   level 2: "head" (pose);                      level 3: "left_hand", "right_hand" (pose).
Result<ik::Model> sampleHumanoid();

// A 24-vertebra spine on a fixed pelvis: 18 swing vertebrae and 6 revolute (torsion) ones, in
// three regions (lumbar 5, thoracic 12, cervical 7), 42 dofs. When `coupled`, equality rows
// q_j - r q_i = 0 chain the same component inside each region (33 rows), leaving 9 free dofs.
// Tasks: level 0 "head_orientation", level 1 "head_position", level 2 "chest_orientation".
Result<ik::Model> sampleSpine(bool coupled);

// The same models built once per process (tests that only read them share one).
const ik::Model& sharedSampleHumanoid();
const ik::Model& sharedSampleSpine(bool coupled);

}  // namespace embody::test
