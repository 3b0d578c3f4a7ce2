// The paper's §5.1 layout (`--model paper`) and the spine measures the full-body experiments
// report: torsion sign changes between regions and the largest swing over its limit.
#include <catch2/catch.hpp>

#include "core/angles.h"
#include "ik/spine/spine_analysis.h"
#include "spine/build_spine.h"
#include "ik/spine/spine_description.h"
#include "ik/spine/spine_model.h"

using namespace embody;
using namespace embody::ik::spine;

namespace {

using embody::test::buildSpineOrFail;

}  // namespace

TEST_CASE("the paper's layout: 17 swing + 7 revolute joints, 32 equality rows, 9 free dofs") {
  auto d = loadSpineModel("paper");
  REQUIRE(d.ok());
  CHECK(d->name == "paper");
  const IsolatedSpine s = buildSpineOrFail(*d);
  const SpineSummary sum = summarize(*d, s);
  CHECK(sum.swing_joints == 17);
  CHECK(sum.revolute_joints == 7);
  CHECK(sum.equalities == 32);
  CHECK(sum.dof_free == 9);
  // It differs from the default in one joint only: vc4 (C4-C5) is a revolute.
  const SpineDescription& full = defaultFullSpine();
  int differing = 0;
  for (size_t k = 0; k < full.sites.size(); ++k)
    if (full.sites[k].swing != d->sites[k].swing) {
      ++differing;
      CHECK(d->sites[k].name == "vc4");
    }
  CHECK(differing == 1);
  CHECK(summarize(full, buildSpineOrFail(full)).equalities == 33);
}

TEST_CASE("torsion sign changes between regions: the last carrier below against the first above") {
  const SpineDescription& d = defaultSimplifiedSpine();
  const IsolatedSpine s = buildSpineOrFail(d);
  // Carriers of torsion: lumbar_middle; thoracic_middle, thoracic_upper; cervical_lower, cervical_upper.
  std::vector<SiteMotion> m(d.sites.size());
  auto set = [&](const char* name, double deg) {
    for (size_t k = 0; k < d.sites.size(); ++k)
      if (d.sites[k].name == name) m[k].torsion = deg * kDeg;
  };
  set("lumbar_middle", 2);
  set("thoracic_middle", 3);
  set("thoracic_upper", 3);
  set("cervical_lower", -1);
  set("cervical_upper", -4);
  CHECK(torsionSignChangesWithinRegions(d, s.joints, m) == 0);
  CHECK(torsionSignChangesBetweenRegions(d, s.joints, m) == 1);  // thoracic + to cervical -
  set("thoracic_middle", -3);
  CHECK(torsionSignChangesWithinRegions(d, s.joints, m) == 1);
  CHECK(torsionSignChangesBetweenRegions(d, s.joints, m) ==
        2);  // lumbar + to thoracic -, thoracic + to cervical -
  // A torsion-less swing site carries nothing: its (ignored) value changes no count.
  set("lumbar_lower", -10);
  CHECK(torsionSignChangesBetweenRegions(d, s.joints, m) == 2);
}

TEST_CASE("the largest swing over its limit reads each direction's own limit") {
  const SpineDescription& d = defaultFullSpine();
  const IsolatedSpine s = buildSpineOrFail(d);
  std::vector<SiteMotion> m(d.sites.size());
  CHECK(maxNormalisedSwing(d, s.joints, m) == 0.0);
  const Eigen::Vector3d& r = s.joints.ranges[0];  // vl5, a swing site
  m[0].s_x = upperLimit(d, Component::Flexion, r[0]);
  CHECK(maxNormalisedSwing(d, s.joints, m) == Approx(1.0));
  m[0].s_x = 0.5 * lowerLimit(d, Component::Flexion, r[0]);  // extension: half of its (smaller) limit
  CHECK(maxNormalisedSwing(d, s.joints, m) == Approx(0.5));
}

TEST_CASE("per-vertebra torsion: each carrier's torsion shared by axial range, summing back to it") {
  for (bool coupled : {true, false}) {
    const SpineDescription& d = defaultSimplifiedSpine();
    SpineOptions o;
    o.coupled = coupled;
    auto s = buildIsolatedSpine(d, o);
    REQUIRE(s.ok());
    std::vector<SiteMotion> m(d.sites.size());
    for (size_t k = 0; k < m.size(); ++k) m[k].torsion = (0.01 + 0.002 * double(k)) * (k % 2 ? 1.0 : -1.0);
    const std::vector<double> t = vertebraTorsion(d, s->joints, m);
    REQUIRE(t.size() == 24);
    std::vector<double> sum(d.sites.size(), 0.0);
    for (size_t v = 0; v < t.size(); ++v) {
      const int site = carrierSite(d, static_cast<int>(v), Component::Torsion, coupled);
      REQUIRE(site >= 0);
      CHECK(((t[v] > 0) == (m[static_cast<size_t>(site)].torsion > 0)));  // the carrier's direction
      sum[static_cast<size_t>(site)] += t[v];
    }
    for (size_t k = 0; k < d.sites.size(); ++k) {
      const bool carries = coupled ? s->joints.sites[k].revolute >= 0 : true;
      CHECK(sum[k] == Approx(carries ? m[k].torsion : 0.0).margin(1e-15));
    }
  }
}
