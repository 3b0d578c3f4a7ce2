#pragma once
// Reading VRM extension JSON defensively: every accessor returns a fallback (and, where the
// caller passes a warning list, says why) instead of throwing on a wrong type, a missing key or
// a non-finite number. Used by the spring-bone, expression and look-at parsers.
#include <cmath>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace embody::avatar::vrm {

using Json = nlohmann::json;

// obj[key], or null when obj is not an object or lacks the key.
inline const Json& member(const Json& obj, const char* key) {
  static const Json kNull;
  if (!obj.is_object()) return kNull;
  const auto it = obj.find(key);
  return it == obj.end() ? kNull : *it;
}

// The array's elements, or an empty array when it is not one.
inline const Json& arrayOf(const Json& v) {
  static const Json kEmpty = Json::array();
  return v.is_array() ? v : kEmpty;
}

// A finite number within [lo, hi]; `fallback` (with a warning naming `what`) otherwise. A null
// (absent) value gives the fallback silently: absent means "the specification's default".
inline float numberIn(const Json& v, float fallback, float lo, float hi, const std::string& what,
                      std::vector<std::string>& warnings) {
  if (v.is_null()) return fallback;
  if (v.is_number()) {
    const double x = v.get<double>();
    if (std::isfinite(x) && x >= lo && x <= hi) return static_cast<float>(x);
  }
  warnings.push_back(what + ": " + v.dump().substr(0, 40) + " is not a number in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]; " + std::to_string(fallback) + " used");
  return fallback;
}

// A vec3 from [x, y, z] (VRM 1.0) or {"x":, "y":, "z":} (VRM 0.x); fallback with a warning.
inline glm::vec3 vec3Of(const Json& v, glm::vec3 fallback, const std::string& what, std::vector<std::string>& warnings) {
  if (v.is_null()) return fallback;
  glm::vec3 r = fallback;
  bool ok = false;
  if (v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number()) {
    r = {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
    ok = true;
  } else if (v.is_object()) {
    ok = true;
    const char* keys[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      const Json& c = member(v, keys[k]);
      if (c.is_number())
        r[k] = c.get<float>();
      else if (!c.is_null())
        ok = false;
    }
  }
  if (ok && std::isfinite(r.x + r.y + r.z) && glm::length(r) < 1e6f) return r;
  warnings.push_back(what + ": " + v.dump().substr(0, 60) + " is not a finite 3-vector; default used");
  return fallback;
}

// A non-negative integer index below `count`, else -1 (with a warning when present but bad).
inline int indexBelow(const Json& v, size_t count, const std::string& what, std::vector<std::string>& warnings) {
  if (v.is_null()) return -1;
  if (v.is_number_integer() || v.is_number_unsigned()) {
    const long long i = v.get<long long>();
    if (i >= 0 && static_cast<unsigned long long>(i) < count) return static_cast<int>(i);
  }
  warnings.push_back(what + ": " + v.dump().substr(0, 40) + " is not an index below " + std::to_string(count));
  return -1;
}

inline std::string stringOr(const Json& v, const std::string& fallback) {
  return v.is_string() ? v.get<std::string>() : fallback;
}

}  // namespace embody::avatar::vrm
