#include "ik/spine/spine_description.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/angles.h"
#include "core/enum_names.h"
#include "ik/spine/spine_default_data.h"

namespace embody::ik::spine {
namespace {

using nlohmann::json;

Error descriptionError(const std::string& message) { return Error{"spine description: " + message}; }

// Small typed readers: each returns an error naming the field and what was expected.
Status readNumber(const json& object, const char* key, const std::string& who, double& out, bool required = true) {
  if (!object.contains(key)) return required ? Status(descriptionError(who + ": missing \"" + key + "\"")) : Status::success();
  const json& v = object.at(key);
  if (!v.is_number()) return descriptionError(who + ": \"" + key + "\" must be a number");
  out = v.get<double>();
  if (!std::isfinite(out)) return descriptionError(who + ": \"" + key + "\" is not finite");
  return Status::success();
}

Status readString(const json& object, const char* key, const std::string& who, std::string& out, bool required = true) {
  if (!object.contains(key)) return required ? Status(descriptionError(who + ": missing \"" + key + "\"")) : Status::success();
  const json& v = object.at(key);
  if (!v.is_string()) return descriptionError(who + ": \"" + key + "\" must be a string");
  out = v.get<std::string>();
  return Status::success();
}

Status readVector3(const json& object, const char* key, const std::string& who, Eigen::Vector3d& out) {
  if (!object.contains(key)) return descriptionError(who + ": missing \"" + key + "\"");
  const json& v = object.at(key);
  if (!v.is_array() || v.size() != 3) return descriptionError(who + ": \"" + key + "\" must be an array of 3 numbers");
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number()) return descriptionError(who + ": \"" + key + "\" must be an array of 3 numbers");
    out[i] = v[i].get<double>();
    if (!std::isfinite(out[i])) return descriptionError(who + ": \"" + key + "\" has a non-finite entry");
  }
  return Status::success();
}

constexpr EnumName<Region> kRegionNames[] = {
    {Region::Lumbar, "lumbar"}, {Region::Thoracic, "thoracic"}, {Region::Cervical, "cervical"}};

Result<Region> parseRegion(const std::string& s, const std::string& who) {
  Region region{};
  if (parseEnumName(kRegionNames, s, region)) return region;
  return descriptionError(who + ": region \"" + s + "\" is not one of lumbar, thoracic, cervical");
}

#define EMBODY_SPINE_TRY(expr)                    \
  do {                                            \
    if (Status s_ = (expr); !s_) return Error{s_.error()}; \
  } while (false)

// Checks everything that parse and withSites share: sites cover the vertebrae once, in order,
// each within one region, and each region keeps all three components.
Status validate(SpineDescription& d) {
  if (d.vertebrae.empty()) return descriptionError("no vertebrae");
  std::set<std::string> names;
  for (size_t i = 0; i < d.vertebrae.size(); ++i) {
    const Vertebra& v = d.vertebrae[i];
    const std::string who = "vertebrae[" + std::to_string(i) + "] (" + v.name + ")";
    if (v.name.empty()) return descriptionError(who + ": empty name");
    if (!names.insert(v.name).second) return descriptionError(who + ": duplicate name");
    if (i > 0 && v.region < d.vertebrae[i - 1].region)
      return descriptionError(who + ": regions must go caudal to cranial (lumbar, thoracic, cervical)");
    for (int c = 0; c < 3; ++c)
      if (!(v.range[c] > 0)) return descriptionError(who + ": every range must be > 0 degrees");
    if (!(v.length > 0)) return descriptionError(who + ": length_m must be > 0");
  }
  for (int r = 0; r < kRegionCount; ++r) {
    bool any = false;
    for (const Vertebra& v : d.vertebrae) any = any || v.region == Region(r);
    if (!any) return descriptionError(std::string("no ") + toString(Region(r)) + " vertebra");
  }
  if (!(d.reference_height > 0)) return descriptionError("reference_height_m must be > 0");
  if (!(d.flexion_share > 0 && d.flexion_share < 1)) return descriptionError("flexion_share must be in (0, 1)");
  if (!(d.band_slack >= 0)) return descriptionError("band_slack_deg must be >= 0");
  if (d.sites.empty()) return descriptionError("no sites");
  int next = 0;
  std::set<std::string> siteNames;
  for (size_t i = 0; i < d.sites.size(); ++i) {
    Site& s = d.sites[i];
    const std::string who = "sites[" + std::to_string(i) + "] (" + s.name + ")";
    if (!siteNames.insert(s.name).second) return descriptionError(who + ": duplicate site name");
    if (s.first != next)
      return descriptionError(who + ": sites must cover the vertebrae in order, each exactly once; expected it to start at " +
                  (next < static_cast<int>(d.vertebrae.size()) ? d.vertebrae[next].name : std::string("(none left)")));
    if (s.count < 1 || s.first + s.count > static_cast<int>(d.vertebrae.size()))
      return descriptionError(who + ": its last vertebra comes before its first or does not exist");
    s.region = d.vertebrae[s.first].region;
    for (int k = s.first; k < s.first + s.count; ++k)
      if (d.vertebrae[k].region != s.region) return descriptionError(who + ": a site must not span two regions");
    if (!s.swing && !s.revolute) return descriptionError(who + ": a site needs a swing or a revolute joint");
    next = s.first + s.count;
  }
  if (next != static_cast<int>(d.vertebrae.size()))
    return descriptionError("sites leave vertebrae from " + d.vertebrae[next].name + " on without a joint");
  for (int r = 0; r < kRegionCount; ++r) {
    bool swing = false, revolute = false;
    for (const Site& s : d.sites) {
      swing = swing || (s.region == Region(r) && s.swing);
      revolute = revolute || (s.region == Region(r) && s.revolute);
    }
    if (!swing) return descriptionError(std::string("the ") + toString(Region(r)) + " region has no swing joint");
    if (!revolute)
      return descriptionError(std::string("the ") + toString(Region(r)) + " region has no revolute joint (its torsion would be lost)");
  }
  std::set<Region> coupled;
  for (const AxisCoupling& a : d.axis_couplings) {
    if (!(a.torsion_per_bending > 0)) return descriptionError("axis_coupling: torsion_per_bending must be > 0");
    if (!coupled.insert(a.region).second)
      return descriptionError(std::string("axis_coupling: the ") + toString(a.region) + " region is listed twice");
  }
  return Status::success();
}

Result<Site> parseSite(const json& js, size_t i, const SpineDescription& d) {
  const std::string who = "sites[" + std::to_string(i) + "]";
  if (!js.is_object()) return descriptionError(who + " must be an object");
  Site s;
  std::string first, last, joints;
  EMBODY_SPINE_TRY(readString(js, "first", who, first));
  last = first;
  EMBODY_SPINE_TRY(readString(js, "last", who, last, false));
  s.name = first;
  EMBODY_SPINE_TRY(readString(js, "name", who, s.name, false));
  EMBODY_SPINE_TRY(readString(js, "joints", who, joints));
  s.first = d.findVertebra(first);
  const int l = d.findVertebra(last);
  if (s.first < 0) return descriptionError(who + ": unknown vertebra \"" + first + "\"");
  if (l < 0) return descriptionError(who + ": unknown vertebra \"" + last + "\"");
  s.count = l - s.first + 1;
  if (joints == "swing") s.swing = true;
  else if (joints == "revolute") s.revolute = true;
  else if (joints == "swing+revolute") s.swing = s.revolute = true;
  else return descriptionError(who + ": joints \"" + joints + "\" is not one of swing, revolute, swing+revolute");
  return s;
}

}  // namespace

const char* toString(Region region) {
  return enumName(kRegionNames, region);
}

constexpr EnumName<Component> kComponentNames[] = {
    {Component::Flexion, "flexion"}, {Component::Bending, "bending"}, {Component::Torsion, "torsion"}};

const char* toString(Component component) {
  return enumName(kComponentNames, component);
}

int SpineDescription::swingCount() const {
  int n = 0;
  for (const Site& s : sites) n += s.swing ? 1 : 0;
  return n;
}

int SpineDescription::revoluteCount() const {
  int n = 0;
  for (const Site& s : sites) n += s.revolute ? 1 : 0;
  return n;
}

int SpineDescription::findVertebra(std::string_view n) const {
  for (size_t i = 0; i < vertebrae.size(); ++i)
    if (vertebrae[i].name == n) return static_cast<int>(i);
  return -1;
}

Result<SpineDescription> parseSpineDescription(const json& j) {
  if (!j.is_object()) return descriptionError("the document must be a JSON object");
  std::string format;
  EMBODY_SPINE_TRY(readString(j, "format", "document", format));
  if (format != "embody-spine") return descriptionError("format must be \"embody-spine\", not \"" + format + "\"");
  double version = 0;
  EMBODY_SPINE_TRY(readNumber(j, "version", "document", version));
  if (version != 1) return descriptionError("version " + std::to_string(version) + " is not supported (expected 1)");
  SpineDescription d;
  EMBODY_SPINE_TRY(readString(j, "name", "document", d.name));
  EMBODY_SPINE_TRY(readNumber(j, "reference_height_m", "document", d.reference_height));
  EMBODY_SPINE_TRY(readVector3(j, "origin_m", "document", d.origin));
  EMBODY_SPINE_TRY(readNumber(j, "flexion_share", "document", d.flexion_share, false));
  double slackDeg = 2.0;
  EMBODY_SPINE_TRY(readNumber(j, "band_slack_deg", "document", slackDeg, false));
  d.band_slack = slackDeg * kDeg;
  if (!j.contains("vertebrae") || !j["vertebrae"].is_array()) return descriptionError("\"vertebrae\" must be an array");
  for (size_t i = 0; i < j["vertebrae"].size(); ++i) {
    const json& jv = j["vertebrae"][i];
    std::string who = "vertebrae[" + std::to_string(i) + "]";
    if (!jv.is_object()) return descriptionError(who + " must be an object");
    Vertebra v;
    EMBODY_SPINE_TRY(readString(jv, "name", who, v.name));
    who += " (" + v.name + ")";
    EMBODY_SPINE_TRY(readString(jv, "level", who, v.level, false));
    std::string region;
    EMBODY_SPINE_TRY(readString(jv, "region", who, region));
    auto r = parseRegion(region, who);
    if (!r) return Error{r.error()};
    v.region = *r;
    Eigen::Vector3d rangeDeg;
    EMBODY_SPINE_TRY(readVector3(jv, "range_deg", who, rangeDeg));
    v.range = rangeDeg * kDeg;
    double ext = 0;
    EMBODY_SPINE_TRY(readNumber(jv, "neutral_extension_deg", who, ext, false));
    v.neutral_extension = ext * kDeg;
    EMBODY_SPINE_TRY(readNumber(jv, "length_m", who, v.length));
    d.vertebrae.push_back(std::move(v));
  }
  if (!j.contains("sites") || !j["sites"].is_array()) return descriptionError("\"sites\" must be an array");
  for (size_t i = 0; i < j["sites"].size(); ++i) {
    auto s = parseSite(j["sites"][i], i, d);
    if (!s) return Error{s.error()};
    d.sites.push_back(std::move(*s));
  }
  if (j.contains("axis_coupling")) {
    if (!j["axis_coupling"].is_array()) return descriptionError("\"axis_coupling\" must be an array");
    for (size_t i = 0; i < j["axis_coupling"].size(); ++i) {
      const json& ja = j["axis_coupling"][i];
      const std::string who = "axis_coupling[" + std::to_string(i) + "]";
      if (!ja.is_object()) return descriptionError(who + " must be an object");
      AxisCoupling a;
      std::string region, side;
      EMBODY_SPINE_TRY(readString(ja, "region", who, region));
      auto r = parseRegion(region, who);
      if (!r) return Error{r.error()};
      a.region = *r;
      EMBODY_SPINE_TRY(readNumber(ja, "torsion_per_bending", who, a.torsion_per_bending));
      EMBODY_SPINE_TRY(readString(ja, "side", who, side));
      if (side != "same" && side != "opposite") return descriptionError(who + ": side must be \"same\" or \"opposite\"");
      a.same_side = side == "same";
      d.axis_couplings.push_back(a);
    }
  }
  EMBODY_SPINE_TRY(validate(d));
  return d;
}

Result<SpineDescription> parseSpineDescriptionText(std::string_view text) {
  json j = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return descriptionError("not valid JSON");
  return parseSpineDescription(j);
}

Result<SpineDescription> loadSpineDescription(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return descriptionError("cannot open '" + path + "'");
  std::stringstream buffer;
  buffer << in.rdbuf();
  auto r = parseSpineDescriptionText(buffer.str());
  if (!r) return Error{r.error() + " (in '" + path + "')"};
  return r;
}

json toJson(const SpineDescription& d) {
  json j;
  j["format"] = "embody-spine";
  j["version"] = 1;
  j["name"] = d.name;
  j["reference_height_m"] = d.reference_height;
  j["origin_m"] = {d.origin.x(), d.origin.y(), d.origin.z()};
  j["flexion_share"] = d.flexion_share;
  j["band_slack_deg"] = d.band_slack / kDeg;
  j["vertebrae"] = json::array();
  for (const Vertebra& v : d.vertebrae)
    j["vertebrae"].push_back({{"name", v.name},
                              {"level", v.level},
                              {"region", toString(v.region)},
                              {"range_deg", {v.range[0] / kDeg, v.range[1] / kDeg, v.range[2] / kDeg}},
                              {"neutral_extension_deg", v.neutral_extension / kDeg},
                              {"length_m", v.length}});
  j["sites"] = json::array();
  for (const Site& s : d.sites)
    j["sites"].push_back({{"name", s.name},
                          {"first", d.vertebrae[s.first].name},
                          {"last", d.vertebrae[s.first + s.count - 1].name},
                          {"joints", s.swing && s.revolute ? "swing+revolute" : s.swing ? "swing" : "revolute"}});
  j["axis_coupling"] = json::array();
  for (const AxisCoupling& a : d.axis_couplings)
    j["axis_coupling"].push_back({{"region", toString(a.region)},
                                  {"torsion_per_bending", a.torsion_per_bending},
                                  {"side", a.same_side ? "same" : "opposite"}});
  return j;
}

const SpineDescription& defaultFullSpine() {
  static const SpineDescription full = [] {
    auto r = parseSpineDescriptionText(detail::kFullSpineJson);
    if (!r) throw std::logic_error("embedded full spine: " + r.error());  // a build defect, caught by tests
    return std::move(*r);
  }();
  return full;
}

const SpineDescription& defaultSimplifiedSpine() {
  static const SpineDescription simplified = [] {
    json j = json::parse(detail::kFullSpineJson);
    j["name"] = "simplified";
    j["sites"] = json::parse(detail::kSimplifiedSitesJson);
    auto r = parseSpineDescription(j);
    if (!r) throw std::logic_error("embedded simplified spine: " + r.error());
    return std::move(*r);
  }();
  return simplified;
}

// The paper's §5.1 count: 32 equality rows = 17 swing + 7 revolute joints (a region with s swing
// and t revolute joints has 2(s - 1) + (t - 1) rows). The paper names the first revolute of each
// region (L2, T8, C6) but not every joint; the seventh revolute is put at vc4 (C4-C5), so the
// neck alternates swing and revolute from C7 up (docs/spine.md, "The paper's layout").
const SpineDescription& paperSpine() {
  static const SpineDescription paper = [] {
    json j = json::parse(detail::kFullSpineJson);
    j["name"] = "paper";
    for (json& site : j["sites"])
      if (site["first"] == "vc4") site["joints"] = "revolute";
    auto r = parseSpineDescription(j);
    if (!r) throw std::logic_error("embedded paper spine: " + r.error());
    return std::move(*r);
  }();
  return paper;
}

Result<SpineDescription> loadSpineModel(const std::string& nameOrPath) {
  if (nameOrPath == "full") return defaultFullSpine();
  if (nameOrPath == "simplified") return defaultSimplifiedSpine();
  if (nameOrPath == "paper") return paperSpine();
  return loadSpineDescription(nameOrPath);
}

Result<SpineDescription> withSites(const SpineDescription& base, const std::vector<SiteSpec>& specs) {
  SpineDescription d = base;
  d.sites.clear();
  for (size_t i = 0; i < specs.size(); ++i) {
    const SiteSpec& spec = specs[i];
    const std::string who = "sites[" + std::to_string(i) + "] (" + spec.name + ")";
    Site s;
    s.name = spec.name;
    s.first = d.findVertebra(spec.first);
    const int last = d.findVertebra(spec.last);
    if (s.first < 0) return descriptionError(who + ": unknown vertebra \"" + spec.first + "\"");
    if (last < 0) return descriptionError(who + ": unknown vertebra \"" + spec.last + "\"");
    s.count = last - s.first + 1;
    s.swing = spec.swing;
    s.revolute = spec.revolute;
    d.sites.push_back(s);
  }
  EMBODY_SPINE_TRY(validate(d));
  return d;
}

int carrierSite(const SpineDescription& d, int vertebra, Component component, bool distribute) {
  int best = -1, bestDistance = 0;
  for (size_t s = 0; s < d.sites.size(); ++s) {
    const Site& site = d.sites[s];
    const int last = site.first + site.count - 1;
    if (!distribute) {
      if (vertebra >= site.first && vertebra <= last) return static_cast<int>(s);
      continue;
    }
    const bool carries = component == Component::Torsion ? site.revolute : site.swing;
    if (!carries || site.region != d.vertebrae[vertebra].region) continue;
    const int distance = vertebra < site.first ? site.first - vertebra : vertebra > last ? vertebra - last : 0;
    if (best < 0 || distance < bestDistance) {  // strict: the caudal site wins a tie
      best = static_cast<int>(s);
      bestDistance = distance;
    }
  }
  return best;
}

std::vector<Eigen::Vector3d> siteRanges(const SpineDescription& d, bool distribute) {
  std::vector<Eigen::Vector3d> ranges(d.sites.size(), Eigen::Vector3d::Zero());
  for (int k = 0; k < static_cast<int>(d.vertebrae.size()); ++k)
    for (int c = 0; c < kComponentCount; ++c)  // validate() guarantees every region has a carrier
      ranges[carrierSite(d, k, Component(c), distribute)][c] += d.vertebrae[k].range[c];
  return ranges;
}

double lowerLimit(const SpineDescription& d, Component c, double range) {
  return c == Component::Flexion ? -(1.0 - d.flexion_share) * range : -range;
}

double upperLimit(const SpineDescription& d, Component c, double range) {
  return c == Component::Flexion ? d.flexion_share * range : range;
}

std::vector<Eigen::Vector3d> neutralCentres(const SpineDescription& d, double height) {
  const double scale = height / d.reference_height;
  std::vector<Eigen::Vector3d> centres;
  centres.reserve(d.vertebrae.size() + 1);
  Eigen::Vector3d p = d.origin * scale;
  double forwardTilt = 0.0;  // of the segment above the current joint, from the vertical
  for (const Vertebra& v : d.vertebrae) {
    centres.push_back(p);
    forwardTilt -= v.neutral_extension;
    p += v.length * scale * Eigen::Vector3d(0.0, std::cos(forwardTilt), std::sin(forwardTilt));
  }
  centres.push_back(p);
  return centres;
}

}  // namespace embody::ik::spine
