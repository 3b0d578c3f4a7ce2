// The procedural mannequin: H-Anim skeleton + swept-tube mesh with smooth weights.
#include "avatar/procedural/default_avatar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <glm/gtc/constants.hpp>
#include <map>

#include "avatar/avatar_loader.h"
#include "core/smoothstep.h"

namespace embody::avatar {
namespace {

using Influences = std::vector<std::pair<int, float>>;  // joint, weight (any order, not normalised)

Influences lerp(const Influences& a, const Influences& b, float t) {
  std::map<int, float> m;
  for (auto [j, w] : a) m[j] += (1.0f - t) * w;
  for (auto [j, w] : b) m[j] += t * w;
  Influences out;
  for (auto [j, w] : m)
    if (w > 1e-6f) out.emplace_back(j, w);
  return out;
}

// Piecewise-linear profile through (x, value) points, clamped at the ends.
float profile(const std::vector<glm::vec2>& pts, float x) {
  if (x <= pts.front().x) return pts.front().y;
  for (size_t i = 1; i < pts.size(); ++i)
    if (x <= pts[i].x)
      return glm::mix(pts[i - 1].y, pts[i].y, (x - pts[i - 1].x) / (pts[i].x - pts[i - 1].x));
  return pts.back().y;
}

class MeshSink {
 public:
  explicit MeshSink(SkinnedMesh& m) : mesh_(m) {}

  uint32_t vertex(const glm::vec3& p, const glm::vec2& uv, Influences w) {
    SkinnedVertex v;
    v.position = p;
    v.uv = uv;
    std::sort(w.begin(), w.end(), [](auto& a, auto& b) { return a.second > b.second; });
    if (w.size() > 4) w.resize(4);
    float sum = 0.0f;
    for (auto& [j, x] : w) sum += x;
    v.weights0 = glm::vec4(0.0f);
    v.joints0 = glm::uvec4(0u);
    for (size_t k = 0; k < w.size(); ++k) {
      v.joints0[static_cast<int>(k)] = static_cast<uint32_t>(w[k].first);
      v.weights0[static_cast<int>(k)] = w[k].second / sum;
    }
    // Put the rounding error on the largest weight so the float sum is 1 to the last bit.
    v.weights0[0] = 1.0f - (v.weights0[1] + v.weights0[2] + v.weights0[3]);
    mesh_.vertices.push_back(v);
    return static_cast<uint32_t>(mesh_.vertices.size() - 1);
  }
  void triangle(uint32_t a, uint32_t b, uint32_t c) { mesh_.indices.insert(mesh_.indices.end(), {a, b, c}); }

 private:
  SkinnedMesh& mesh_;
};

struct Station {
  glm::vec3 centre;
  float ru, rv;  // radius across (lateral) and along the reference axis
  Influences weights;
};

using WeightFn = std::function<Influences(const glm::vec3&, const Influences&)>;

struct TubeRing {
  glm::vec3 c, t;
  float ru, rv;
  Influences w;
  float s;
};

// The rings of a tube through the stations, `spacing` apart along the path (s: arc length).
std::vector<TubeRing> tubeRings(const std::vector<Station>& st, float spacing) {
  auto tangentAt = [&](size_t i) {
    const glm::vec3 a = st[i == 0 ? 0 : i - 1].centre, b = st[std::min(i + 1, st.size() - 1)].centre;
    return glm::normalize(b - a);
  };
  std::vector<TubeRing> rings;
  float s = 0.0f;
  for (size_t i = 0; i + 1 < st.size(); ++i) {
    const float len = glm::length(st[i + 1].centre - st[i].centre);
    const int k = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    for (int j = 0; j < k; ++j) {
      const float t = static_cast<float>(j) / static_cast<float>(k);
      rings.push_back({glm::mix(st[i].centre, st[i + 1].centre, t),
                       glm::normalize(glm::mix(tangentAt(i), tangentAt(i + 1), t)),
                       glm::mix(st[i].ru, st[i + 1].ru, t), glm::mix(st[i].rv, st[i + 1].rv, t),
                       lerp(st[i].weights, st[i + 1].weights, t), s + t * len});
    }
    s += len;
  }
  rings.push_back(
      {st.back().centre, tangentAt(st.size() - 1), st.back().ru, st.back().rv, st.back().weights, s});
  return rings;
}

// The rings with domes added at both ends: rings shrinking on a quarter ellipse.
std::vector<TubeRing> withDomes(const std::vector<TubeRing>& rings, float domeStart, float domeEnd) {
  constexpr int kDome = 4;
  std::vector<TubeRing> all;
  const TubeRing first = rings.front(), last = rings.back();
  auto shrunk = [](TubeRing r, float phi, float along) {
    r.c += r.t * (std::sin(phi) * along);
    r.ru *= std::cos(phi);
    r.rv *= std::cos(phi);
    return r;
  };
  for (int d = kDome; d >= 1; --d)
    all.push_back(shrunk(first, glm::half_pi<float>() * static_cast<float>(d) / (kDome + 1), -domeStart));
  all.insert(all.end(), rings.begin(), rings.end());
  for (int d = 1; d <= kDome; ++d)
    all.push_back(shrunk(last, glm::half_pi<float>() * static_cast<float>(d) / (kDome + 1), domeEnd));
  return all;
}

// A closed tube through the stations with domed ends. Rings are spaced `spacing` apart; the ring
// frame is (u, v, t) with t the path tangent and v as close to `ref` as possible.
void addTube(MeshSink& sink, const std::vector<Station>& st, int radial, float spacing, const glm::vec3& ref,
             float domeStart, float domeEnd, const WeightFn& weightFn = nullptr) {
  const std::vector<TubeRing> rings = tubeRings(st, spacing);
  const std::vector<TubeRing> all = withDomes(rings, domeStart, domeEnd);
  const TubeRing first = rings.front(), last = rings.back();
  auto weightsAt = [&](const glm::vec3& p, const Influences& w) { return weightFn ? weightFn(p, w) : w; };
  std::vector<uint32_t> ringStart;
  for (const TubeRing& r : all) {
    glm::vec3 u = glm::cross(ref, r.t);
    u = glm::length(u) > 1e-6f ? glm::normalize(u) : glm::vec3(1, 0, 0);
    const glm::vec3 v = glm::cross(r.t, u);
    ringStart.push_back(0);
    for (int j = 0; j < radial; ++j) {
      const float th = glm::two_pi<float>() * static_cast<float>(j) / static_cast<float>(radial);
      const glm::vec3 p = r.c + r.ru * std::cos(th) * u + r.rv * std::sin(th) * v;
      const uint32_t id =
          sink.vertex(p, {static_cast<float>(j) / static_cast<float>(radial), r.s}, weightsAt(p, r.w));
      if (j == 0) ringStart.back() = id;
    }
  }
  for (size_t r = 0; r + 1 < all.size(); ++r)
    for (int j = 0; j < radial; ++j) {
      const uint32_t jn = static_cast<uint32_t>((j + 1) % radial);
      const uint32_t a = ringStart[r] + static_cast<uint32_t>(j), b = ringStart[r] + jn;
      const uint32_t c = ringStart[r + 1] + jn, d = ringStart[r + 1] + static_cast<uint32_t>(j);
      sink.triangle(a, b, c);
      sink.triangle(a, c, d);
    }
  // A pole vertex closes each dome.
  const glm::vec3 p0 = first.c - first.t * domeStart, p1 = last.c + last.t * domeEnd;
  const uint32_t pole0 = sink.vertex(p0, {0.5f, -domeStart}, weightsAt(p0, first.w));
  const uint32_t pole1 = sink.vertex(p1, {0.5f, last.s + domeEnd}, weightsAt(p1, last.w));
  const uint32_t lastRing = ringStart.back();
  for (int j = 0; j < radial; ++j) {
    const uint32_t jn = static_cast<uint32_t>((j + 1) % radial);
    sink.triangle(pole0, ringStart[0] + jn, ringStart[0] + static_cast<uint32_t>(j));
    sink.triangle(pole1, lastRing + static_cast<uint32_t>(j), lastRing + jn);
  }
}

// An ellipsoid with semi-axes along the model axes, weights per vertex.
void addEllipsoid(MeshSink& sink, const glm::vec3& c, const glm::vec3& r, int stacks, int slices,
                  const std::function<Influences(const glm::vec3&)>& weights) {
  std::vector<Station> st;
  // Rings from bottom to top pole, as a tube along +Y whose domes close the poles.
  for (int i = 1; i < stacks; ++i) {
    const float phi = glm::pi<float>() * static_cast<float>(i) / static_cast<float>(stacks);
    st.push_back(
        {c + glm::vec3(0.0f, -std::cos(phi) * r.y, 0.0f), std::sin(phi) * r.x, std::sin(phi) * r.z, {}});
  }
  const float step = glm::pi<float>() / static_cast<float>(stacks);
  const float pole = r.y * (1.0f - std::cos(step));
  // A tube with rings exactly at the stations (spacing larger than any step) and short domes.
  std::vector<Station> stations = st;
  MeshSink& s = sink;
  addTube(s, stations, slices, 1e9f, glm::vec3(0, 0, 1), pole, pole,
          [&](const glm::vec3& p, const Influences&) { return weights(p); });
}

struct JointDef {
  const char* name;
  const char* parent;
  glm::vec3 pos;  // model-space rest position
};

// H-Anim LOA-3 default centres for the spine (spine.md §4, x = 0); limbs after the same
// specification's proportions, arms hanging about 10 degrees out.
std::vector<JointDef> jointTable() {
  std::vector<JointDef> t = {
      {"humanoid_root", nullptr, {0, 0.8240f, 0.0277f}},
      {"sacroiliac", "humanoid_root", {0, 0.9149f, 0.0016f}},
      {"vl5", "humanoid_root", {0, 1.0568f, -0.0776f}},
      {"vl4", "vl5", {0, 1.0925f, -0.0787f}},
      {"vl3", "vl4", {0, 1.1276f, -0.0796f}},
      {"vl2", "vl3", {0, 1.1546f, -0.0800f}},
      {"vl1", "vl2", {0, 1.1912f, -0.0805f}},
      {"vt12", "vl1", {0, 1.2278f, -0.0808f}},
      {"vt11", "vt12", {0, 1.2679f, -0.0810f}},
      {"vt10", "vt11", {0, 1.2848f, -0.0822f}},
      {"vt9", "vt10", {0, 1.3126f, -0.0838f}},
      {"vt8", "vt9", {0, 1.3382f, -0.0845f}},
      {"vt7", "vt8", {0, 1.3625f, -0.0833f}},
      {"vt6", "vt7", {0, 1.3866f, -0.0800f}},
      {"vt5", "vt6", {0, 1.4102f, -0.0745f}},
      {"vt4", "vt5", {0, 1.4320f, -0.0675f}},
      {"vt3", "vt4", {0, 1.4583f, -0.0570f}},
      {"vt2", "vt3", {0, 1.4761f, -0.0484f}},
      {"vt1", "vt2", {0, 1.4951f, -0.0387f}},
      {"vc7", "vt1", {0, 1.5132f, -0.0301f}},
      {"vc6", "vc7", {0, 1.5357f, -0.0143f}},
      {"vc5", "vc6", {0, 1.5520f, -0.0082f}},
      {"vc4", "vc5", {0, 1.5662f, -0.0084f}},
      {"vc3", "vc4", {0, 1.5800f, -0.0103f}},
      {"vc2", "vc3", {0, 1.5928f, -0.0103f}},
      {"vc1", "vc2", {0, 1.6144f, -0.0034f}},
      {"skullbase", "vc1", {0, 1.6209f, 0.0236f}},
  };
  struct Side {
    const char* prefix;
    float sign;
  };
  static const char* names[2][8] = {{"l_hip", "l_knee", "l_ankle", "l_metatarsal", "l_sternoclavicular",
                                     "l_shoulder", "l_elbow", "l_wrist"},
                                    {"r_hip", "r_knee", "r_ankle", "r_metatarsal", "r_sternoclavicular",
                                     "r_shoulder", "r_elbow", "r_wrist"}};
  for (int side = 0; side < 2; ++side) {
    const float x = side == 0 ? 1.0f : -1.0f;  // left is +X when facing +Z
    const char* const* n = names[side];
    t.push_back({n[0], "sacroiliac", {x * 0.0961f, 0.9124f, -0.0001f}});
    t.push_back({n[1], n[0], {x * 0.1040f, 0.4867f, 0.0108f}});
    t.push_back({n[2], n[1], {x * 0.0950f, 0.0821f, -0.0112f}});
    t.push_back({n[3], n[2], {x * 0.1000f, 0.0200f, 0.1250f}});
    t.push_back({n[4], "vt1", {x * 0.0300f, 1.4500f, 0.0300f}});
    t.push_back({n[5], n[4], {x * 0.1850f, 1.4400f, -0.0400f}});
    t.push_back({n[6], n[5], {x * 0.2350f, 1.1450f, -0.0550f}});
    t.push_back({n[7], n[6], {x * 0.2700f, 0.8860f, -0.0300f}});
  }
  return t;
}

// The hand's rest geometry with fingers: the fingers hang straight along the forearm (`down`),
// the knuckles spread across the palm's width (`across`, the thumb side: forward), the palm faces
// the thigh (`palm`). The middle knuckle lies on the forearm's line, so the hand bone's direction
// (towards its first child) is the same as without fingers.
struct HandGeometry {
  glm::vec3 down, across, palm;
};

HandGeometry handGeometry(const glm::vec3& wrist, const glm::vec3& elbow) {
  const float sx = wrist.x > 0.0f ? 1.0f : -1.0f;  // left hand at +X
  HandGeometry g;
  g.down = glm::normalize(wrist - elbow);
  g.across = glm::normalize(glm::vec3(0, 0, 1) - g.down.z * g.down);
  g.palm = glm::normalize(glm::cross(g.down, g.across));
  if (glm::dot(g.palm, glm::vec3(-sx, 0, 0)) < 0.0f) g.palm = -g.palm;  // towards the body
  return g;
}

struct FingerShape {
  const char* name;  // H-Anim 1.1 stem: <side>_<name>1..3
  float knuckleDown, knuckleAcross;
  float lengths[3];
  float radius;
};
// Middle first: it becomes the wrist's first child (see HandGeometry).
constexpr FingerShape kFingerShapes[4] = {
    {"middle", 0.092f, 0.000f, {0.044f, 0.028f, 0.022f}, 0.0090f},
    {"index", 0.088f, 0.021f, {0.040f, 0.024f, 0.020f}, 0.0086f},
    {"ring", 0.088f, -0.019f, {0.041f, 0.026f, 0.021f}, 0.0083f},
    {"pinky", 0.080f, -0.036f, {0.032f, 0.019f, 0.018f}, 0.0072f},
};
constexpr float kThumbLengths[3] = {0.040f, 0.032f, 0.026f};

// Thumb joints (CMC, MCP, IP) and tip: out of the palm's thumb side, forward and a little palmar.
std::array<glm::vec3, 4> thumbPoints(const glm::vec3& wrist, const HandGeometry& g) {
  const glm::vec3 cmc = wrist + g.down * 0.022f + g.across * 0.018f + g.palm * 0.010f;
  const glm::vec3 d1 = glm::normalize(g.down * 0.55f + g.across * 0.7f + g.palm * 0.35f);
  const glm::vec3 d2 = glm::normalize(g.down * 0.75f + g.across * 0.55f + g.palm * 0.3f);
  const glm::vec3 mcp = cmc + d1 * kThumbLengths[0], ip = mcp + d2 * kThumbLengths[1];
  return {cmc, mcp, ip, ip + d2 * kThumbLengths[2]};
}

void appendFingerJoints(std::vector<JointDef>& defs, std::vector<std::string>& names) {
  auto posOf = [&](const std::string& n) {
    for (const auto& d : defs)
      if (n == d.name) return d.pos;
    return glm::vec3(0.0f);
  };
  struct Pending {
    std::string name, parent;
    glm::vec3 pos;
  };
  std::vector<Pending> pending;
  for (const char* side : {"l_", "r_"}) {
    const std::string s = side;
    const glm::vec3 wr = posOf(s + "wrist"), el = posOf(s + "elbow");
    const HandGeometry g = handGeometry(wr, el);
    for (const auto& f : kFingerShapes) {
      glm::vec3 p = wr + g.down * f.knuckleDown + g.across * f.knuckleAcross;
      std::string parent = s + "wrist";
      for (int k = 0; k < 3; ++k) {
        const std::string name = s + f.name + std::to_string(k + 1);
        pending.push_back({name, parent, p});
        parent = name;
        p += g.down * f.lengths[k];
      }
    }
    const auto t = thumbPoints(wr, g);
    std::string parent = s + "wrist";
    for (int k = 0; k < 3; ++k) {
      const std::string name = s + "thumb" + std::to_string(k + 1);
      pending.push_back({name, parent, t[static_cast<size_t>(k)]});
      parent = name;
    }
  }
  // Names (and parents) are stored once, then the JointDefs point into that storage.
  names.reserve(pending.size() * 2);
  for (const auto& q : pending) {
    names.push_back(q.name);
    names.push_back(q.parent);
  }
  for (size_t i = 0; i < pending.size(); ++i)
    defs.push_back({names[2 * i].c_str(), names[2 * i + 1].c_str(), pending[i].pos});
}

// Palm and five skinned fingers for the hand of `prefix` ("l_" / "r_"): every phalanx blends
// into its neighbours at the joints, the palm follows the wrist.
void addFingeredHand(MeshSink& sink, const Skeleton& skeleton, const std::vector<glm::vec3>& pos,
                     const std::string& prefix, int wristJoint, const glm::vec3& wr, const glm::vec3& el) {
  const HandGeometry g = handGeometry(wr, el);
  auto handOnly = [&](const glm::vec3&) { return Influences{{wristJoint, 1.0f}}; };
  addEllipsoid(sink, wr + g.down * 0.050f - g.across * 0.006f, {0.018f, 0.055f, 0.046f}, 14, 20, handOnly);
  auto chainTube = [&](const std::array<int, 3>& joints, const glm::vec3& tip, float radius,
                       float startInset) {
    std::vector<Station> st;
    const glm::vec3 p0 = pos[static_cast<size_t>(joints[0])];
    const glm::vec3 first = glm::normalize(pos[static_cast<size_t>(joints[1])] - p0);
    st.push_back({p0 - first * startInset, radius * 1.1f, radius, {{wristJoint, 1.0f}}});
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 a = pos[static_cast<size_t>(joints[static_cast<size_t>(k)])];
      const glm::vec3 b = k < 2 ? pos[static_cast<size_t>(joints[static_cast<size_t>(k) + 1])] : tip;
      const float r = radius * (1.0f - 0.1f * float(k));
      const int parent = k == 0 ? wristJoint : joints[static_cast<size_t>(k) - 1];
      st.push_back({a, r * 1.05f, r, {{parent, 0.5f}, {joints[static_cast<size_t>(k)], 0.5f}}});
      st.push_back({glm::mix(a, b, 0.5f), r, r * 0.95f, {{joints[static_cast<size_t>(k)], 1.0f}}});
    }
    st.push_back({tip, radius * 0.8f, radius * 0.75f, {{joints[2], 1.0f}}});
    addTube(sink, st, 10, 0.008f, g.palm, radius * 0.8f, radius * 0.8f);
  };
  for (const auto& f : kFingerShapes) {
    std::array<int, 3> j{};
    for (int k = 0; k < 3; ++k)
      j[static_cast<size_t>(k)] = skeleton.find(prefix + f.name + std::to_string(k + 1));
    const glm::vec3 tip = pos[static_cast<size_t>(j[2])] + g.down * f.lengths[2];
    chainTube(j, tip, f.radius, 0.02f);
  }
  std::array<int, 3> thumb{};
  for (int k = 0; k < 3; ++k)
    thumb[static_cast<size_t>(k)] = skeleton.find(prefix + "thumb" + std::to_string(k + 1));
  chainTube(thumb, thumbPoints(wr, g)[3], 0.011f, 0.005f);
}

// The skeleton of the joint table (parents first) with each joint's model-space rest position,
// and the inverse bind matrices (rest rotations are identity).
std::vector<glm::vec3> addSkeleton(AvatarAsset& a, const std::vector<JointDef>& defs) {
  std::vector<glm::vec3> pos;
  for (const auto& d : defs) {
    Joint j;
    j.name = d.name;
    j.parent = d.parent ? a.skeleton.find(d.parent) : -1;
    j.rest.translation = d.pos - (j.parent >= 0 ? pos[static_cast<size_t>(j.parent)] : glm::vec3(0.0f));
    a.skeleton.joints.push_back(j);
    pos.push_back(d.pos);
  }
  a.mesh.inverseBind.resize(pos.size());
  for (size_t i = 0; i < pos.size(); ++i) {
    a.mesh.inverseBind[i] = glm::mat4(1.0f);
    a.mesh.inverseBind[i][3] = glm::vec4(-pos[i], 1.0f);
  }
  a.skinJointCount = static_cast<int>(pos.size());
  return pos;
}

// The mannequin's joints by name: index and model-space rest position.
struct JointLookup {
  const Skeleton& skeleton;
  const std::vector<glm::vec3>& pos;
  int J(const std::string& n) const { return skeleton.find(n); }
  glm::vec3 P(const std::string& n) const { return pos[static_cast<size_t>(skeleton.find(n))]; }
};

// Hat functions over stations (height, joint): a vertex at height y blends the two stations
// around it, so weights change linearly from one bone to the next.
Influences hat(const std::vector<std::pair<float, int>>& stations, float y) {
  if (y <= stations.front().first) return {{stations.front().second, 1.0f}};
  for (size_t i = 1; i < stations.size(); ++i)
    if (y <= stations[i].first) {
      const float t = (y - stations[i - 1].first) / (stations[i].first - stations[i - 1].first);
      return {{stations[i - 1].second, 1.0f - t}, {stations[i].second, t}};
    }
  return {{stations.back().second, 1.0f}};
}

// Torso, neck and head, skinned along the vertebrae.
void addTrunkAndHead(MeshSink& sink, const JointLookup& k) {
  // Each vertebra bone's station is the middle of the bone (its joint to the next one up).
  const char* spineNames[] = {"vl5", "vl4", "vl3", "vl2", "vl1", "vt12", "vt11",     "vt10", "vt9",
                              "vt8", "vt7", "vt6", "vt5", "vt4", "vt3",  "vt2",      "vt1",  "vc7",
                              "vc6", "vc5", "vc4", "vc3", "vc2", "vc1",  "skullbase"};
  std::vector<std::pair<float, int>> spineStations = {{0.97f, k.J("sacroiliac")}};
  for (int i = 0; i + 1 < 25; ++i)
    spineStations.push_back({0.5f * (k.P(spineNames[i]).y + k.P(spineNames[i + 1]).y), k.J(spineNames[i])});
  spineStations.push_back({1.64f, k.J("skullbase")});

  // Torso: elliptical sections by height; upper outer vertices follow the clavicles.
  const std::vector<glm::vec2> halfWidth = {{0.80f, 0.150f}, {0.88f, 0.170f}, {0.98f, 0.160f},
                                            {1.08f, 0.132f}, {1.20f, 0.140f}, {1.32f, 0.158f},
                                            {1.42f, 0.172f}, {1.47f, 0.150f}, {1.51f, 0.075f}};
  const std::vector<glm::vec2> halfDepth = {{0.80f, 0.085f}, {0.90f, 0.105f}, {1.00f, 0.098f},
                                            {1.08f, 0.090f}, {1.25f, 0.105f}, {1.35f, 0.108f},
                                            {1.45f, 0.085f}, {1.51f, 0.055f}};
  const std::vector<glm::vec2> centreZ = {{0.80f, 0.005f}, {0.95f, -0.005f}, {1.10f, -0.005f},
                                          {1.30f, 0.010f}, {1.45f, -0.015f}, {1.51f, -0.025f}};
  std::vector<Station> torso;
  for (float y = 0.80f; y <= 1.5101f; y += 0.015f)
    torso.push_back({{0.0f, y, profile(centreZ, y)}, profile(halfWidth, y), profile(halfDepth, y), {}});
  const int lClav = k.J("l_sternoclavicular"), rClav = k.J("r_sternoclavicular");
  addTube(sink, torso, 36, 0.015f, glm::vec3(0, 0, 1), 0.04f, 0.02f,
          [&](const glm::vec3& p, const Influences&) {
            Influences w = hat(spineStations, p.y);
            const float s = smoothstep(0.09f, 0.17f, std::abs(p.x)) * smoothstep(1.34f, 1.43f, p.y);
            for (auto& [j, x] : w) x *= 1.0f - s;
            if (s > 0.0f) w.emplace_back(p.x > 0 ? lClav : rClav, s);
            return w;
          });

  // Neck.
  std::vector<Station> neck;
  for (float y = 1.47f; y <= 1.6101f; y += 0.014f)
    neck.push_back({{0.0f, y, glm::mix(-0.030f, 0.005f, (y - 1.47f) / 0.14f)}, 0.056f, 0.058f, {}});
  addTube(sink, neck, 28, 0.014f, glm::vec3(0, 0, 1), 0.02f, 0.02f,
          [&](const glm::vec3& p, const Influences&) { return hat(spineStations, p.y); });

  // Head and nose (facing +Z).
  const int skull = k.J("skullbase");
  auto headOnly = [&](const glm::vec3&) { return Influences{{skull, 1.0f}}; };
  addEllipsoid(sink, {0.0f, 1.645f, 0.030f}, {0.078f, 0.110f, 0.100f}, 28, 36, headOnly);
  addEllipsoid(sink, {0.0f, 1.632f, 0.122f}, {0.015f, 0.024f, 0.022f}, 8, 12, headOnly);
}

glm::vec3 along(const glm::vec3& a, const glm::vec3& b, float d) { return a + glm::normalize(b - a) * d; }

// One leg (thigh to ankle) and its foot; `p` is the side's prefix ("l_" / "r_").
void addLeg(MeshSink& sink, const JointLookup& k, const std::string& p) {
  const float sx = p == "l_" ? 1.0f : -1.0f;
  const int hipJ = k.J(p + "hip"), kneeJ = k.J(p + "knee"), ankleJ = k.J(p + "ankle"), toeJ = k.J(p + "metatarsal");
  const glm::vec3 hip = k.P(p + "hip"), knee = k.P(p + "knee"), ankle = k.P(p + "ankle");
  const int pelvis = k.J("sacroiliac");
  std::vector<Station> leg = {
      {hip + glm::vec3(0, 0.03f, 0), 0.080f, 0.080f, {{pelvis, 0.5f}, {hipJ, 0.5f}}},
      {along(hip, knee, 0.06f), 0.086f, 0.086f, {{hipJ, 1.0f}}},
      {glm::mix(hip, knee, 0.45f), 0.072f, 0.074f, {{hipJ, 1.0f}}},
      {along(knee, hip, 0.05f), 0.055f, 0.056f, {{hipJ, 1.0f}}},
      {knee, 0.050f, 0.053f, {{hipJ, 0.5f}, {kneeJ, 0.5f}}},
      {along(knee, ankle, 0.05f), 0.050f, 0.052f, {{kneeJ, 1.0f}}},
      {along(knee, ankle, 0.13f), 0.054f, 0.060f, {{kneeJ, 1.0f}}},
      {along(ankle, knee, 0.07f), 0.032f, 0.034f, {{kneeJ, 1.0f}}},
      {ankle, 0.030f, 0.032f, {{kneeJ, 0.5f}, {ankleJ, 0.5f}}},
      {ankle - glm::vec3(0, 0.03f, 0), 0.030f, 0.032f, {{ankleJ, 1.0f}}},
  };
  addTube(sink, leg, 24, 0.02f, glm::vec3(0, 0, 1), 0.03f, 0.02f);
  // Foot: heel to toe along +Z; the front third bends with the toes.
  addEllipsoid(sink, {ankle.x + sx * 0.004f, 0.045f, 0.060f}, {0.045f, 0.045f, 0.130f}, 16, 24,
               [&](const glm::vec3& v) {
                 const float t = smoothstep(0.09f, 0.14f, v.z);
                 return Influences{{ankleJ, 1.0f - t}, {toeJ, t}};
               });
}

// One arm (shoulder to wrist) and its hand: a mitten with a thumb, or five skinned fingers.
void addArm(MeshSink& sink, const JointLookup& k, const std::string& p, bool fingers) {
  const float sx = p == "l_" ? 1.0f : -1.0f;
  const int clavJ = k.J(p + "sternoclavicular"), shJ = k.J(p + "shoulder"), elJ = k.J(p + "elbow"),
            wrJ = k.J(p + "wrist");
  const glm::vec3 sh = k.P(p + "shoulder"), el = k.P(p + "elbow"), wr = k.P(p + "wrist");
  std::vector<Station> arm = {
      {sh, 0.052f, 0.050f, {{clavJ, 0.5f}, {shJ, 0.5f}}},
      {along(sh, el, 0.06f), 0.050f, 0.049f, {{shJ, 1.0f}}},
      {glm::mix(sh, el, 0.5f), 0.045f, 0.044f, {{shJ, 1.0f}}},
      {along(el, sh, 0.04f), 0.037f, 0.037f, {{shJ, 1.0f}}},
      {el, 0.036f, 0.037f, {{shJ, 0.5f}, {elJ, 0.5f}}},
      {along(el, wr, 0.04f), 0.038f, 0.039f, {{elJ, 1.0f}}},
      {glm::mix(el, wr, 0.4f), 0.034f, 0.037f, {{elJ, 1.0f}}},
      {along(wr, el, 0.03f), 0.024f, 0.028f, {{elJ, 1.0f}}},
      {wr, 0.022f, 0.027f, {{elJ, 0.5f}, {wrJ, 0.5f}}},
  };
  addTube(sink, arm, 20, 0.02f, glm::vec3(0, 0, 1), 0.045f, 0.015f);
  if (fingers) {
    addFingeredHand(sink, k.skeleton, k.pos, p, wrJ, wr, el);
    return;
  }
  // Hand (palm towards the thigh) and thumb pointing forward.
  auto handOnly = [&](const glm::vec3&) { return Influences{{wrJ, 1.0f}}; };
  const glm::vec3 down = glm::normalize(wr - el);
  addEllipsoid(sink, wr + down * 0.085f, {0.020f, 0.092f, 0.045f}, 16, 20, handOnly);
  addEllipsoid(sink, wr + down * 0.055f + glm::vec3(-sx * 0.004f, 0.0f, 0.042f), {0.012f, 0.036f, 0.013f},
               8, 12, handOnly);
}

// Normals from the generated surfaces (area-weighted; every part is a closed shell).
void computeNormals(SkinnedMesh& mesh) {
  std::vector<glm::vec3> acc(mesh.vertices.size(), glm::vec3(0.0f));
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t i0 = mesh.indices[t], i1 = mesh.indices[t + 1], i2 = mesh.indices[t + 2];
    const glm::vec3 n = glm::cross(mesh.vertices[i1].position - mesh.vertices[i0].position,
                                   mesh.vertices[i2].position - mesh.vertices[i0].position);
    acc[i0] += n;
    acc[i1] += n;
    acc[i2] += n;
  }
  for (size_t i = 0; i < acc.size(); ++i) {
    const float len = glm::length(acc[i]);
    mesh.vertices[i].normal = len > 1e-20f ? acc[i] / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }
}

}  // namespace

AvatarAsset buildDefaultAvatar() {
  return buildDefaultAvatar(DefaultAvatarOptions{});
}

AvatarAsset buildDefaultAvatar(const DefaultAvatarOptions& options) {
  AvatarAsset a;
  a.format = AvatarFormat::Procedural;
  auto defs = jointTable();
  std::vector<std::string> fingerNames;  // owns the names the JointDefs point at
  if (options.fingers) appendFingerJoints(defs, fingerNames);
  const std::vector<glm::vec3> pos = addSkeleton(a, defs);
  const JointLookup joints{a.skeleton, pos};
  MeshSink sink(a.mesh);
  addTrunkAndHead(sink, joints);
  for (const std::string side : {"l_", "r_"}) {
    addLeg(sink, joints, side);
    addArm(sink, joints, side, options.fingers);
  }
  computeNormals(a.mesh);
  Material m;
  m.name = "mannequin";
  m.baseColorFactor = glm::vec4(0.72f, 0.72f, 0.74f, 1.0f);
  a.materials.push_back(m);
  Primitive prim;
  prim.indexCount = static_cast<uint32_t>(a.mesh.indices.size());
  prim.material = 0;
  a.mesh.primitives.push_back(prim);
  // The H-Anim names map by name; no user bone map can be malformed here.
  (void)prepareAvatar(a, "");
  return a;
}

}  // namespace embody::avatar
