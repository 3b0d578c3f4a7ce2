#include "eval/report.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

namespace embody::eval {

namespace {

namespace fs = std::filesystem;

double cm(double metres) { return 100.0 * metres; }

nlohmann::json metricsJson(const MethodRun& r) {
  const Metrics& m = r.metrics;
  nlohmann::json j;
  for (int g = 0; g < kGroupCount; ++g)
    j["mpjpe_cm"][groupName(Group(g))] = {{"mean", cm(m.mpjpe[size_t(g)].mean)}, {"p95", cm(m.mpjpe[size_t(g)].p95)}};
  j["mpjre_deg"] = m.mpjreDegrees;
  j["mpjve_cm_s"] = cm(m.mpjve);
  j["jitter_m_s3"] = m.jitter;
  j["clip_jitter_m_s3"] = m.clipJitter;
  for (int g = 0; g < kGroupCount; ++g)
    j["jitter_by_group_m_s3"][groupName(Group(g))] = {{"solution", m.groupJitter[size_t(g)]},
                                                      {"clip", m.clipGroupJitter[size_t(g)]}};
  j["foot_skating_cm_s"] = cm(m.footSkating);
  j["clip_foot_skating_cm_s"] = cm(m.clipFootSkating);
  j["contact_frames"] = m.contactFrames;
  j["knee_reverse_frames"] = m.kneeReverseFrames;
  j["elbow_reverse_frames"] = m.elbowReverseFrames;
  j["torsion_sign_change_frames"] = m.torsionSignChangeFrames;
  j["clip_torsion_sign_change_frames"] = m.clipTorsionSignChangeFrames;
  j["collapsed_frames"] = m.collapsedFrames;
  j["seconds"] = r.seconds;
  return j;
}

Status writeCsv(const ClipEval& e, const fs::path& dir) {
  std::ofstream f(dir / "frames.csv");
  f << "frame,time_s";
  for (const auto& r : e.runs)
    for (int g = 0; g < kGroupCount; ++g) f << "," << methodName(r.method) << "_" << groupName(Group(g)) << "_cm";
  for (const auto& r : e.runs)
    for (const char* flag : {"knee_reversed", "elbow_reversed", "collapsed"}) f << "," << methodName(r.method) << "_" << flag;
  f << "\n";
  char buf[64];
  for (int i = 0; i < e.frames; ++i) {
    std::snprintf(buf, sizeof buf, "%d,%.6f", i, double(i) / e.fps);
    f << buf;
    for (const auto& r : e.runs)
      for (int g = 0; g < kGroupCount; ++g) {
        const auto& v = r.metrics.perFrame[size_t(g)];
        std::snprintf(buf, sizeof buf, ",%.4f", size_t(i) < v.size() ? cm(v[size_t(i)]) : 0.0);
        f << buf;
      }
    for (const auto& r : e.runs) {
      const auto& flags = r.metrics.perFrameFlags;
      const unsigned char b = size_t(i) < flags.size() ? flags[size_t(i)] : 0;
      f << ',' << int((b & kKneeReversed) != 0) << ',' << int((b & kElbowReversed) != 0) << ',' << int((b & kCollapsed) != 0);
    }
    f << "\n";
  }
  std::ofstream jf(dir / "joints.csv");
  jf << "joint";
  for (const auto& r : e.runs) jf << "," << methodName(r.method) << "_cm";
  // The bias columns after every method's mean error (joints.gp plots those by column number).
  for (const auto& r : e.runs)
    if (!r.metrics.perJointBias.empty())
      for (const char* axis : {"forward", "left", "up"}) jf << "," << methodName(r.method) << "_" << axis << "_cm";
  jf << "\n";
  for (int j : e.skeleton.groups[kAll]) {
    jf << e.jointNames[size_t(j)];
    for (const auto& r : e.runs) {
      std::snprintf(buf, sizeof buf, ",%.4f", cm(r.metrics.perJointError[size_t(j)]));
      jf << buf;
    }
    for (const auto& r : e.runs)
      if (!r.metrics.perJointBias.empty()) {
        const glm::dvec3 b = r.metrics.perJointBias[size_t(j)];
        std::snprintf(buf, sizeof buf, ",%.4f,%.4f,%.4f", cm(b.x), cm(b.y), cm(b.z));
        jf << buf;
      }
    jf << "\n";
  }
  if (!f || !jf) return Error{"cannot write the CSV files in " + dir.string()};
  return Status::success();
}

// gnuplot scripts: error over time per group (the coupled run, with the other methods' "all"),
// per-joint mean error bars for every method.
void writeScripts(const ClipEval& e, const fs::path& dir) {
  std::ofstream g(dir / "errors.gp");
  g << "set terminal pngcairo size 1100,520 noenhanced\nset output 'errors.png'\nset datafile separator ','\n"
       "set key outside right\nset xlabel 'time (s)'\nset ylabel 'joint position error (cm)'\nset grid\n"
       "set title 'MPJPE over time, " << fs::path(e.clip).filename().string() << "'\nplot ";
  // Columns: 1 frame, 2 time, then methods x groups.
  int col = 3;
  bool first = true;
  for (const auto& r : e.runs)
    for (int gi = 0; gi < kGroupCount; ++gi, ++col) {
      if (r.method != Method::Coupled && gi != kAll) continue;
      g << (first ? "" : ", \\\n     ") << "'frames.csv' using 2:" << col << " with lines title '" << methodName(r.method)
        << " " << groupName(Group(gi)) << "'";
      first = false;
    }
  g << "\n";
  std::ofstream j(dir / "joints.gp");
  j << "set terminal pngcairo size 1400,560 noenhanced\nset output 'joints.png'\nset datafile separator ','\n"
       "set style data histograms\nset style histogram clustered gap 1\nset style fill solid 0.8 border -1\n"
       "set xtics rotate by -60 font ',8'\nset ylabel 'mean position error (cm)'\nset grid ytics\nset key top left\n"
       "set title 'per-joint MPJPE'\nplot ";
  for (size_t k = 0; k < e.runs.size(); ++k)
    j << (k ? ", " : "") << "'joints.csv' using " << k + 2 << (k == 0 ? ":xtic(1)" : "") << " skip 1 title '"
      << methodName(e.runs[k].method) << "'";
  j << "\n";
}

}  // namespace

Result<std::vector<std::string>> writeReport(const ClipEval& e, const ReportOptions& o, const fs::path& dir) {
  std::vector<std::string> notes;
  nlohmann::json j;
  j["clip"] = e.clip;
  j["fps"] = e.fps;
  j["frames"] = e.frames;
  j["trackers"] = o.trackers;
  j["ik_iterations"] = o.ikIterations;
  j["mpjre_definition"] = "geodesic angle between world joint rotations, degrees";
  j["joints_scored"] = e.skeleton.groups[kAll].size();
  for (const auto& r : e.runs) j["methods"][methodName(r.method)] = metricsJson(r);
  j["notes"] = e.notes;
  std::ofstream(dir / "metrics.json") << j.dump(2) << "\n";
  if (auto s = writeCsv(e, dir); !s) return Error{s.error()};
  writeScripts(e, dir);
  if (o.plots) {
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
      notes.push_back("gnuplot not found: errors.gp and joints.gp written, not drawn");
    } else {
      const std::string cmd = "cd '" + dir.string() + "' && gnuplot errors.gp joints.gp 2>&1";
      if (std::system(cmd.c_str()) != 0) notes.push_back("gnuplot failed on errors.gp / joints.gp");
    }
  }
  return notes;
}

std::string methodTable(const ClipEval& e) {
  std::string out = "method      MPJPE cm (p95)   hands   feet    head    upper   lower   root    MPJRE deg  MPJVE cm/s  "
                    "jitter m/s3 (clip)   skate cm/s  knee/elbow rev  collapsed\n";
  char buf[400];
  for (const auto& r : e.runs) {
    const Metrics& m = r.metrics;
    auto g = [&](Group x) { return cm(m.mpjpe[size_t(x)].mean); };
    std::snprintf(buf, sizeof buf, "%-10s  %6.2f (%6.2f)  %6.2f  %6.2f  %6.2f  %6.2f  %6.2f  %6.2f  %9.2f  %10.1f  %8.1f (%7.1f)  %10.2f  %5d/%-5d      %5d\n",
                  methodName(r.method), g(kAll), cm(m.mpjpe[kAll].p95), g(kHands), g(kFeet), g(kHead), g(kUpper), g(kLower),
                  g(kRoot), m.mpjreDegrees, cm(m.mpjve), m.jitter, m.clipJitter, cm(m.footSkating), m.kneeReverseFrames,
                  m.elbowReverseFrames, m.collapsedFrames);
    out += buf;
  }
  return out;
}

}  // namespace embody::eval
