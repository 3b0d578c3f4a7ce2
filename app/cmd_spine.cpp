// embody spine describe: what a spine model is made of — vertebrae, sites, joints by type, dofs
// before and after coupling, constraint rows — for the built-in models or a user's JSON file.
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <nlohmann/json.hpp>
#include <string>

#include "core/angles.h"
#include "app/args.h"
#include "ik/spine/spine_description.h"
#include "ik/spine/spine_model.h"

namespace {

using namespace embody;

const char* jointsOf(const ik::spine::Site& s, bool coupled) {
  if (!coupled) return "ball";
  return s.swing && s.revolute ? "swing+revolute" : s.swing ? "swing" : "revolute";
}

// The model as one JSON object (what --json prints and the text is made from).
nlohmann::json describe(const ik::spine::SpineDescription& desc, const ik::spine::IsolatedSpine& model,
                        const ik::spine::SpineSummary& s, const ik::spine::SpineOptions& options, double height) {
  // Which joints carry limits (the first of each region, or all).
  auto limited = [&](ik::JointId j) {
    if (j < 0) return false;
    const auto& d = model.model.joints[j].desc;
    if (!d.upper.empty() && std::isfinite(d.upper[0])) return true;
    for (const auto& row : model.model.inequalities)
      if (row.terms.size() == 1 && row.terms[0].dof.joint == j) return true;
    return false;
  };
  nlohmann::json j;
  j["model"] = desc.name;
  j["coupled"] = options.coupled;
  j["axis_coupling"] = options.axis_coupling;
  j["check_all_limits"] = options.check_all_limits;
  j["height_m"] = height;
  j["vertebrae"] = s.vertebrae;
  j["sites"] = s.sites;
  j["swing_joints"] = s.swing_joints;
  j["revolute_joints"] = s.revolute_joints;
  j["ball_joints"] = s.ball_joints;
  j["dof_total"] = s.dof_total;
  j["dof_free"] = s.dof_free;
  j["equalities"] = s.equalities;
  j["axis_equalities"] = s.axis_equalities;
  j["inequalities"] = s.inequalities;
  j["band_inequalities"] = s.band_inequalities;
  j["limit_inequalities"] = s.limit_inequalities;
  j["band_slack_deg"] = desc.band_slack / kDeg;
  j["site_list"] = nlohmann::json::array();
  for (size_t k = 0; k < desc.sites.size(); ++k) {
    const ik::spine::Site& site = desc.sites[k];
    const auto& sj = model.joints.sites[k];
    const Eigen::Vector3d r = model.joints.ranges[k] / kDeg;
    nlohmann::json vs = nlohmann::json::array();
    for (int v = site.first; v < site.first + site.count; ++v) vs.push_back(desc.vertebrae[v].name);
    j["site_list"].push_back({{"name", site.name},
                              {"region", ik::spine::toString(site.region)},
                              {"vertebrae", vs},
                              {"joints", jointsOf(site, options.coupled)},
                              {"range_deg", {{"flexion_extension", r[0]}, {"bending", r[1]}, {"torsion", r[2]}}},
                              {"limited", limited(sj.swing) || limited(sj.revolute) || limited(sj.ball)}});
  }
  return j;
}

void printText(const nlohmann::json& j, const ik::spine::SpineDescription& desc, const ik::spine::SpineSummary& s,
               const ik::spine::SpineOptions& options, double height) {
  std::printf("spine model '%s' (%s%s%s), height %.2f m\n", desc.name.c_str(), options.coupled ? "coupled" : "uncoupled",
              options.axis_coupling && options.coupled ? ", axis coupling" : "",
              options.check_all_limits ? ", all limits" : "", height);
  std::printf("  %d vertebrae on %d joint sites\n\n", s.vertebrae, s.sites);
  std::printf("  %-16s %-9s %-12s %-15s %24s  %s\n", "site", "region", "vertebrae", "joints", "range deg (FE  LB  AR)",
              "limits");
  for (const auto& site : j["site_list"]) {
    const auto& vs = site["vertebrae"];
    std::string span = vs.front().get<std::string>();
    if (vs.size() > 1) span += "-" + vs.back().get<std::string>();
    std::printf("  %-16s %-9s %-12s %-15s %10.1f %5.1f %5.1f      %s\n", site["name"].get<std::string>().c_str(),
                site["region"].get<std::string>().c_str(), span.c_str(), site["joints"].get<std::string>().c_str(),
                site["range_deg"]["flexion_extension"].get<double>(), site["range_deg"]["bending"].get<double>(),
                site["range_deg"]["torsion"].get<double>(), site["limited"].get<bool>() ? "checked" : "-");
  }
  std::printf("\njoints: %d swing, %d revolute, %d ball\n", s.swing_joints, s.revolute_joints, s.ball_joints);
  std::printf("dofs:   %d before coupling, %d free after\n", s.dof_total, s.dof_free);
  std::printf("rows:   %d equalities (%d cross-axis), %d inequalities (%d inter-region band, slack %.1f deg; %d joint limit)\n",
              s.equalities, s.axis_equalities, s.inequalities, s.band_inequalities, desc.band_slack / kDeg,
              s.limit_inequalities);
}

int runSpine(app::Argv argv) {
  app::Args args("embody spine",
                 "Describes a spine model: its vertebrae and joint sites, joints by type, dofs before and after "
                 "coupling, and the equality and inequality rows (Raunhardt & Boulic 2008).");
  args.positional("action", "describe");
  args.option("model", "full|simplified|paper|FILE",
              "the built-in full (24 sites), simplified (8 sites) or paper (§5.1: 7 revolutes) model, or a JSON file",
              "full");
  args.flag("uncoupled", "every site a ball joint with its own limits, no coupling rows");
  args.flag("axis-coupling", "add the cross-axis rows (torsion follows lateral bending)");
  args.flag("check-all-limits", "limits on every joint, not only the first of each region");
  args.option("height", "METRES", "body height the spine is scaled to", "1.75");
  args.flag("json", "print one JSON object instead of text");
  args.flag("dump", "print the model's JSON description (a starting point for your own file) and stop");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  if (args.get("action") != "describe") {
    return app::usageError("unknown action '" + args.get("action") + "' (expected: describe)");
  }
  double height = 0;
  try {
    height = args.number("height");
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }

  auto desc = ik::spine::loadSpineModel(args.get("model"));
  if (!desc) {
    std::fprintf(stderr, "error: %s\n", desc.error().c_str());
    return 1;
  }
  if (args.has("dump")) {
    std::printf("%s\n", ik::spine::toJson(*desc).dump(2).c_str());
    return 0;
  }
  ik::spine::SpineOptions options;
  options.coupled = !args.has("uncoupled");
  options.axis_coupling = args.has("axis-coupling");
  options.check_all_limits = args.has("check-all-limits");
  auto model = ik::spine::buildIsolatedSpine(*desc, options, height);
  if (!model) {
    std::fprintf(stderr, "error: %s\n", model.error().c_str());
    return 1;
  }
  const ik::spine::SpineSummary s = ik::spine::summarize(*desc, *model);
  const nlohmann::json j = describe(*desc, *model, s, options, height);
  if (args.has("json"))
    std::printf("%s\n", j.dump(2).c_str());
  else
    printText(j, *desc, s, options, height);
  return 0;
}

}  // namespace

EMBODY_COMMAND("spine", "describe a coupled spine model (vertebrae, joints, dofs, constraint rows)", runSpine);
