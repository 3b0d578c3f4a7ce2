// `embody experiment isolated-spine` (Raunhardt & Boulic 2008, §5.1): the spine alone, coupled vs
// uncoupled, plus the inter-region band-slack sweep (ik/spine/isolated_experiment.h).
#include <cstdio>

#include "core/angles.h"
#include "app/experiments.h"
#include "ik/spine/isolated_experiment.h"

namespace embody::app::experiment {
namespace {

// Figure 7 of the paper: task errors and joint variation per iteration (log scale).
std::string convergencePlots() {
  return R"gp(clip(x) = (x > 1e-12 ? x : 1e-12)

# Figure 7: task errors and joint variation per iteration.
)gp" +
         multiplotFigure("fig7_convergence.png", "1,3", "Isolated spine: convergence, coupled (9 free dofs) vs uncoupled (72 dofs)") +
         R"gp(set grid
set key top right
set logscale y
set format y '10^{%L}'
set xlabel 'iteration'
)gp" +
         runsPanels({{"neck position error (m)", "position task (priority 1)", "iterations", "1:(clip($3))", "lines lw 2"},
                     {"head orientation error (deg)", "orientation task (priority 0)", "iterations", "1:(clip($4))", "lines lw 2"},
                     {"|{/Symbol D}q| (rad)", "joint variation norm", "iterations", "1:(clip($5))", "lines lw 2"}}) +
         R"gp(unset multiplot
unset logscale y
set format y '%g'
)gp";
}

// Figure 8: how the swing is distributed over the vertebrae.
std::string swingPlots() {
  return R"gp(
# Figure 8: how the swing is distributed over the vertebrae.
)gp" +
         multiplotFigure("fig8_swing.png", "1,3", "Isolated spine: swing and torsion per vertebra (swing: s_x flexion, s_y lateral bending)") +
         R"gp(set title 'swing components (deg)'
set xlabel 's_x (flexion +forward)'
set ylabel 's_y (lateral bending +left)'
set key top left
plot 'coupled_vertebrae.csv' skip 1 using 4:5 with linespoints pt 7 ps 1.2 lw 1.5 lc rgb '#1f77b4' title 'coupled', \
     'uncoupled_vertebrae.csv' skip 1 using 4:5 with linespoints pt 5 ps 1.0 lw 1.5 lc rgb '#d62728' title 'uncoupled'
set title 'swing / joint limit (0 = swing-less revolute site)'
set xlabel 'vertebra (caudal to cranial)'
set ylabel 'normalised swing'
set yrange [-1.1:1.1]
set key top right
set xtics rotate by 90 right font ',8'
plot 'coupled_vertebrae.csv' skip 1 using 1:8:xtic(2) with linespoints pt 7 lw 2 lc rgb '#1f77b4' title 'coupled s_y', \
     'uncoupled_vertebrae.csv' skip 1 using 1:8 with linespoints pt 5 lw 2 lc rgb '#d62728' title 'uncoupled s_y', \
     'coupled_vertebrae.csv' skip 1 using 1:7 with linespoints pt 6 dt 2 lc rgb '#1f77b4' title 'coupled s_x', \
     'uncoupled_vertebrae.csv' skip 1 using 1:7 with linespoints pt 4 dt 2 lc rgb '#d62728' title 'uncoupled s_x'
set autoscale y
set title 'torsion (deg)'
set ylabel 'torsion (+ front to the left)'
set key top left
plot 'coupled_vertebrae.csv' skip 1 using 1:6:xtic(2) with linespoints pt 7 lw 2 lc rgb '#1f77b4' title 'coupled', \
     'uncoupled_vertebrae.csv' skip 1 using 1:6 with linespoints pt 5 lw 2 lc rgb '#d62728' title 'uncoupled', \
     0 with lines lc rgb 'gray' notitle
unset multiplot
set xtics norotate font ''

)gp";
}

// Figure 6 (the final spine shapes) and the band slack sweep.
std::string shapeAndSlackPlots() {
  return R"gp(# Figure 6: the final spine shapes, front and side views (same scale on both axes).
set terminal pngcairo size 1200,820 font 'Sans,11'
)gp" +
         multiplotFigure("fig6_shapes.png", "1,2", "Isolated spine: final shapes (neck pulled to the left, head orientation kept)") +
         R"gp(set size ratio -1
set key bottom right box opaque
set xtics 0.05
set ytics 0.05
set yrange [0.2:0.85]
set title 'front view'
set xlabel 'x (m, + character left)'
set ylabel 'y (m, up)'
set xrange [-0.1:0.2]
plot 'coupled_shape.csv' skip 1 using 3:4 with linespoints dt 2 pt 1 ps 0.6 lw 1.5 lc rgb 'gray40' title 'rest', \
     'coupled_shape.csv' skip 1 using 6:7 with linespoints pt 7 ps 0.8 lw 2 lc rgb '#1f77b4' title 'coupled', \
     'uncoupled_shape.csv' skip 1 using 6:7 with linespoints pt 5 ps 0.7 lw 2 lc rgb '#d62728' title 'uncoupled', \
     'target.csv' skip 1 using 1:2 with points pt 3 ps 2.5 lw 2 lc rgb 'black' title 'neck target'
set title 'side view'
set xlabel 'z (m, + forward)'
set xrange [-0.25:0.05]
plot 'coupled_shape.csv' skip 1 using 5:4 with linespoints dt 2 pt 1 ps 0.6 lw 1.5 lc rgb 'gray40' title 'rest', \
     'coupled_shape.csv' skip 1 using 8:7 with linespoints pt 7 ps 0.8 lw 2 lc rgb '#1f77b4' title 'coupled', \
     'uncoupled_shape.csv' skip 1 using 8:7 with linespoints pt 5 ps 0.7 lw 2 lc rgb '#d62728' title 'uncoupled', \
     'target.csv' skip 1 using 3:2 with points pt 3 ps 2.5 lw 2 lc rgb 'black' title 'neck target'
unset multiplot

# The inter-region band slack (a value the paper does not give): the coupled run per slack.
set terminal pngcairo size 900,520 font 'Sans,11'
set output 'fig_band_slack.png'
set size noratio
set size 1,1
unset key
set key top right box
set autoscale
set xtics autofreq
set ytics autofreq
set title 'Coupled spine: neck position error after the run vs inter-region band slack'
set xlabel 'band slack s (deg): |q_j - r q_i| <= s between regions'
set ylabel 'neck position error (m)'
set key top right
plot 'band_slack_sweep.csv' skip 1 using 1:2 with linespoints pt 7 lw 2 lc rgb '#1f77b4' title 'coupled'
)gp";
}

// Figures 6, 7 and 8 of the paper, from the CSV files written beside the script.
std::string isolatedSpinePlots() {
  return gnuplotHeader("isolated-spine", "size 1500,520") + convergencePlots() + swingPlots() + shapeAndSlackPlots();
}

void writeRun(const fs::path& dir, const ik::spine::ExperimentRun& run, std::string& error) {
  std::string it = "iteration,time_us,position_error_m,orientation_error_deg,dq_norm_rad\n";
  char line[256];
  for (const ik::spine::IterationSample& s : run.samples) {
    std::snprintf(line, sizeof line, "%d,%.3f,%.9g,%.9g,%.9g\n", s.iteration, s.time_us, s.position_error,
                  s.orientation_error / kDeg, s.step_norm);
    it += line;
  }
  const ik::spine::SpineDescription& d = run.description;
  std::string vs = "index,site,region,s_x_deg,s_y_deg,torsion_deg,s_x_norm,s_y_norm\n";
  std::string shape = "index,joint,rest_x,rest_y,rest_z,final_x,final_y,final_z\n";
  for (size_t k = 0; k < d.sites.size(); ++k) {
    const ik::spine::SiteMotion& m = run.motion[k];
    const Eigen::Vector3d& r = run.joints.ranges[k];
    auto norm = [&](ik::spine::Component c, double v) {
      const double range = r[static_cast<int>(c)];
      if (range <= 0) return 0.0;
      return v / (v >= 0 ? ik::spine::upperLimit(d, c, range) : -ik::spine::lowerLimit(d, c, range));
    };
    std::snprintf(line, sizeof line, "%zu,%s,%s,%.6f,%.6f,%.6f,%.6f,%.6f\n", k, d.sites[k].name.c_str(),
                  ik::spine::toString(d.sites[k].region), m.s_x / kDeg, m.s_y / kDeg, m.torsion / kDeg,
                  norm(ik::spine::Component::Flexion, m.s_x), norm(ik::spine::Component::Bending, m.s_y));
    vs += line;
  }
  for (size_t k = 0; k < run.final_centres.size(); ++k) {
    const Eigen::Vector3d& a = run.rest_centres[k];
    const Eigen::Vector3d& b = run.final_centres[k];
    const std::string name = k < d.sites.size() ? d.sites[k].name : "skullbase";
    std::snprintf(line, sizeof line, "%zu,%s,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", k, name.c_str(), a.x(), a.y(),
                  a.z(), b.x(), b.y(), b.z());
    shape += line;
  }
  if (!writeFile(dir / (run.variant + "_iterations.csv"), it) ||
      !writeFile(dir / (run.variant + "_vertebrae.csv"), vs) ||
      !writeFile(dir / (run.variant + "_shape.csv"), shape))
    error = "cannot write the " + run.variant + " CSV files in " + dir.string();
}

std::string sweepCsv(const std::vector<ik::spine::SlackSweepPoint>& sweep) {
  std::string csv =
      "band_slack_deg,position_error_m,orientation_error_deg,swing_spread,torsion_sign_changes\n";
  for (const ik::spine::SlackSweepPoint& p : sweep) {
    char row[160];
    std::snprintf(row, sizeof row, "%.2f,%.9g,%.9g,%.9g,%d\n", p.slack_deg, p.position_error,
                  p.orientation_error / kDeg, p.swing_spread, p.torsion_sign_changes);
    csv += row;
  }
  return csv;
}

}  // namespace

int runIsolatedSpine(const IsolatedOptions& o, nlohmann::json& summary) {
  auto result = ik::spine::runIsolatedSpineExperiment(o.model, o.experiment);
  if (!result) return fail(result.error());
  std::vector<double> slacks;
  for (int i = 0; i <= 10; ++i) slacks.push_back(0.5 * i);  // 0..5 degrees
  auto sweep = ik::spine::sweepBandSlack(o.model, o.experiment, slacks);
  if (!sweep) return fail(sweep.error());
  std::string error;
  if (!makeFolder(o.common.out, error)) return fail(error);
  writeRun(o.common.out, result->coupled, error);
  writeRun(o.common.out, result->uncoupled, error);
  summary = ik::spine::experimentSummary(*result, o.experiment);
  summary["band_slack_sweep"] = ik::spine::sweepSummary(*sweep);
  summary["setup"]["band_slack_deg"] = o.model.band_slack / kDeg;
  summary["setup"]["model"] = o.model.name;
  summary["coupled"]["equality_rows"] = result->coupled.joints.equalities;
  char target[128];
  std::snprintf(target, sizeof target, "x,y,z\n%.6f,%.6f,%.6f\n", result->neck_target.x(),
                result->neck_target.y(), result->neck_target.z());
  if (error.empty() && (!writeFile(o.common.out / "summary.json", summary.dump(2) + "\n") ||
                        !writeFile(o.common.out / "target.csv", target) ||
                        !writeFile(o.common.out / "band_slack_sweep.csv", sweepCsv(*sweep))))
    error = "cannot write in " + o.common.out.string();
  if (!error.empty()) return fail(error);
  for (const char* v : {"coupled", "uncoupled"}) {
    const auto& s = summary[v];
    std::printf(
        "%-9s position error %.4f m, orientation error %.2g deg, %.1f us/iteration, swing spread %.3g, "
        "torsion sign changes %d\n",
        v, s["final_position_error_m"].get<double>(), s["final_orientation_error_deg"].get<double>(),
        s["mean_iteration_us"].get<double>(), s["swing_spread"].get<double>(),
        s["torsion_sign_changes_within_regions"].get<int>());
  }
  for (const ik::spine::SlackSweepPoint& p : *sweep)
    std::printf("band slack %.1f deg: coupled neck error %.4f m\n", p.slack_deg, p.position_error);
  if (!o.common.plots) {
    std::printf("wrote CSV and summary.json to %s (plots skipped)\n", o.common.out.string().c_str());
    return 0;
  }
  if (auto e = runGnuplot(o.common.out, "plots.gp", isolatedSpinePlots()); !e.empty()) return fail(e);
  std::printf(
      "wrote CSV, summary.json and fig6_shapes.png, fig7_convergence.png, fig8_swing.png, fig_band_slack.png "
      "to %s\n",
      o.common.out.string().c_str());
  return 0;
}

}  // namespace embody::app::experiment
