#include "tracking/trace.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

namespace embody::tracking {

namespace {

// JSON has no NaN or Infinity, but trace writers in other languages emit them (Python's json
// module does). Replace those bare words outside strings by null so the line still parses and the
// tracker becomes invalid instead of the whole file failing.
std::string nonFiniteToNull(const std::string& line) {
  std::string out;
  out.reserve(line.size());
  bool inString = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (inString) {
      out += c;
      if (c == '\\' && i + 1 < line.size()) out += line[++i];
      else if (c == '"') inString = false;
      continue;
    }
    if (c == '"') {
      inString = true;
      out += c;
      continue;
    }
    auto word = [&](std::string_view w) { return line.compare(i, w.size(), w) == 0; };
    if (word("-Infinity")) { out += "null"; i += 8; continue; }
    if (word("Infinity")) { out += "null"; i += 7; continue; }
    if (word("-NaN")) { out += "null"; i += 3; continue; }
    if (word("NaN")) { out += "null"; i += 2; continue; }
    out += c;
  }
  return out;
}

// Reads n numbers; a null or non-finite entry makes the result "not finite" (ok stays true).
bool readNumbers(const nlohmann::json& a, size_t n, float* out, bool& finite, std::string& error,
                 const char* what) {
  if (!a.is_array() || a.size() != n) {
    error = std::string("\"") + what + "\" must be an array of " + std::to_string(n) + " numbers";
    return false;
  }
  for (size_t i = 0; i < n; ++i) {
    if (a[i].is_null()) {
      finite = false;
      out[i] = 0.0f;
    } else if (a[i].is_number()) {
      const double v = a[i].get<double>();
      if (!std::isfinite(v) || std::abs(v) > 1e6) finite = false;
      out[i] = static_cast<float>(v);
    } else {
      error = std::string("\"") + what + "\" must be an array of " + std::to_string(n) + " numbers";
      return false;
    }
  }
  return true;
}

bool readTracker(const nlohmann::json& j, TrackerPose& pose, std::string& error) {
  if (!j.is_object()) {
    error = "must be an object {\"p\": [x,y,z], \"q\": [x,y,z,w], \"valid\": true}";
    return false;
  }
  bool valid = true;
  if (auto v = j.find("valid"); v != j.end()) {
    if (!v->is_boolean()) {
      error = "\"valid\" must be true or false";
      return false;
    }
    valid = v->get<bool>();
  }
  bool finite = true;
  float p[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1};
  const auto pj = j.find("p"), qj = j.find("q");
  if (valid && (pj == j.end() || qj == j.end())) {
    error = "a valid tracker needs both \"p\" and \"q\"";
    return false;
  }
  if (pj != j.end() && !pj->is_null() && !readNumbers(*pj, 3, p, finite, error, "p")) return false;
  if (qj != j.end() && !qj->is_null() && !readNumbers(*qj, 4, q, finite, error, "q")) return false;
  if ((pj != j.end() && pj->is_null()) || (qj != j.end() && qj->is_null())) finite = false;
  pose.position = glm::vec3(p[0], p[1], p[2]);
  pose.orientation = glm::quat(q[3], q[0], q[1], q[2]);
  pose.valid = valid && finite;
  if (pose.valid && !isUsable(pose)) pose.valid = false;  // e.g. a zero quaternion
  if (pose.valid) pose.orientation = glm::normalize(pose.orientation);
  return true;
}

// A hand's optional "trigger" (0..1): anything else (not a number, out of range) clamps to it,
// as a controller's analogue value would.
float readTrigger(const nlohmann::json& tracker) {
  if (!tracker.is_object()) return 0.0f;
  const auto t = tracker.find("trigger");
  if (t == tracker.end() || !t->is_number()) return 0.0f;
  const double v = t->get<double>();
  return std::isfinite(v) ? static_cast<float>(std::clamp(v, 0.0, 1.0)) : 0.0f;
}

void appendNumber(std::string& s, double v, const char* fmt) {
  if (!std::isfinite(v)) {
    s += "null";
    return;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  s += buf;
}

}  // namespace

Result<Trace> parseTrace(std::istream& in, const std::string& name) {
  Trace trace;
  std::string line;
  size_t lineNo = 0;
  auto fail = [&](const std::string& msg) { return Error{name + ":" + std::to_string(lineNo) + ": " + msg}; };
  while (true) {
    line.clear();
    // Bounded read: a line longer than kMaxTraceLineBytes is an error, not an allocation.
    char c;
    bool any = false;
    while (in.get(c)) {
      any = true;
      if (c == '\n') break;
      if (line.size() >= kMaxTraceLineBytes)
        return Error{name + ":" + std::to_string(lineNo + 1) + ": line longer than " +
                     std::to_string(kMaxTraceLineBytes) + " bytes"};
      line += c;
    }
    if (!any) break;
    ++lineNo;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(nonFiniteToNull(line));
    } catch (const nlohmann::json::exception& e) {
      // parse_error, and out_of_range for a number too large for a double (1e999).
      std::string what = e.what();
      if (auto p = what.find("syntax error"); p != std::string::npos) what = what.substr(p);
      if (auto p = what.find("number overflow"); p != std::string::npos) what = what.substr(p);
      return fail("not valid JSON: " + what);
    }
    if (!j.is_object()) return fail("expected a JSON object per line");
    if (j.contains("embody_trace") && !j.contains("t")) {
      if (!trace.samples.empty()) return fail("header line after the first sample");
      if (auto s = j.find("source"); s != j.end() && s->is_string()) trace.source = s->get<std::string>();
      if (auto h = j.find("user_height"); h != j.end() && h->is_number())
        trace.userHeight = static_cast<float>(h->get<double>());
      continue;
    }
    const auto t = j.find("t");
    if (t == j.end() || !t->is_number()) return fail("missing number \"t\" (seconds)");
    const double time = t->get<double>();
    if (!std::isfinite(time)) return fail("\"t\" is not finite");
    if (!trace.samples.empty() && time < trace.samples.back().time)
      return fail("time goes backwards (" + std::to_string(time) + " s after " +
                  std::to_string(trace.samples.back().time) + " s)");
    PoseSample s;
    s.time = time;
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "t") continue;
      const auto id = trackerFromKey(it.key());
      if (!id) {
        if (trace.notes.size() < 8)
          trace.notes.push_back(name + ":" + std::to_string(lineNo) + ": unknown key \"" + it.key() + "\" ignored");
        continue;
      }
      std::string error;
      if (!readTracker(it.value(), s[*id], error)) return fail("\"" + it.key() + "\": " + error);
      if (*id == TrackerId::LeftHand || *id == TrackerId::RightHand)
        s.triggers[*id == TrackerId::LeftHand ? 0 : 1] = readTrigger(it.value());
      trace.trackers.set(*id);
    }
    trace.samples.push_back(s);
  }
  if (trace.samples.empty()) return Error{name + ": no samples (expected one JSON object per line with \"t\")"};
  return trace;
}

Result<Trace> readTrace(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return Error{path + ": cannot open the trace file"};
  return parseTrace(f, path);
}

std::string formatTraceLine(const PoseSample& sample, TrackerMask trackers) {
  std::string s = "{\"t\": ";
  appendNumber(s, sample.time, "%.6f");
  for (auto id : kAllTrackers) {
    if (!trackers.has(id)) continue;
    const TrackerPose& p = sample[id];
    s += ", \"";
    s += trackerKey(id);
    s += "\": {\"p\": [";
    for (int i = 0; i < 3; ++i) {
      if (i) s += ", ";
      appendNumber(s, p.position[i], "%.6f");
    }
    s += "], \"q\": [";
    const float q[4] = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
    for (int i = 0; i < 4; ++i) {
      if (i) s += ", ";
      appendNumber(s, q[i], "%.7f");
    }
    s += "], \"valid\": ";
    s += p.valid ? "true}" : "false}";
  }
  s += "}";
  return s;
}

TraceWriter::~TraceWriter() {
  if (file_) std::fclose(file_);
}

Status TraceWriter::open(const std::string& path, TrackerMask trackers, const std::string& source, float userHeight) {
  if (file_) std::fclose(file_);
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) return Error{path + ": cannot open for writing"};
  path_ = path;
  trackers_ = trackers;
  nlohmann::json header = {{"embody_trace", 1}, {"source", source}, {"user_height", userHeight}};
  const std::string h = header.dump() + "\n";
  if (std::fputs(h.c_str(), file_) < 0) return Error{path + ": write failed"};
  return {};
}

Status TraceWriter::write(const PoseSample& sample) {
  if (!file_) return Error{"trace writer is not open"};
  const std::string line = formatTraceLine(sample, trackers_) + "\n";
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size()) return Error{path_ + ": write failed"};
  return {};
}

Status TraceWriter::close() {
  if (!file_) return {};
  const bool ok = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok) return Error{path_ + ": write failed on close"};
  return {};
}

TraceSource::TraceSource(Trace trace, std::string name) : trace_(std::move(trace)), name_(std::move(name)) {}

double TraceSource::duration() const {
  if (trace_.samples.empty()) return 0.0;
  return trace_.samples.back().time - trace_.samples.front().time;
}

double TraceSource::nativeRate() const {
  const size_t n = trace_.samples.size();
  const double d = duration();
  return n > 1 && d > 0.0 ? static_cast<double>(n - 1) / d : 0.0;
}

PoseSample TraceSource::sample(double time) {
  const auto& ss = trace_.samples;
  PoseSample out;
  out.time = time;
  if (ss.empty()) return out;
  const double t = ss.front().time + (std::isfinite(time) ? time : 0.0);
  auto hi = std::upper_bound(ss.begin(), ss.end(), t, [](double v, const PoseSample& s) { return v < s.time; });
  if (hi == ss.begin()) {
    out.trackers = ss.front().trackers;
    return out;
  }
  if (hi == ss.end()) {
    out.trackers = ss.back().trackers;
    return out;
  }
  const PoseSample& a = *(hi - 1);
  const PoseSample& b = *hi;
  const double span = b.time - a.time;
  const float u = span > 0.0 ? static_cast<float>((t - a.time) / span) : 0.0f;
  for (auto id : kAllTrackers) {
    if (a[id].valid && b[id].valid) out[id] = interpolate(a[id], b[id], u);
    else out[id] = a[id];
  }
  return out;
}

}  // namespace embody::tracking
