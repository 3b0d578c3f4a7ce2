#include "avatar/bvh/bvh.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <fstream>

#include "core/frame_rate.h"

namespace embody::avatar {

namespace {

// Splits the text into lines, each line into whitespace-separated tokens (views into the text).
class Lexer {
 public:
  explicit Lexer(std::string_view text) : text_(text) {}

  bool nextLine(std::vector<std::string_view>& tokens, std::string_view& raw) {
    if (pos_ >= text_.size()) return false;
    // A line ends at LF, CR LF or a lone CR (old Mac tools write CR only).
    size_t end = text_.find_first_of("\r\n", pos_);
    if (end == std::string_view::npos) end = text_.size();
    raw = text_.substr(pos_, end - pos_);
    pos_ = end + (end + 1 < text_.size() && text_[end] == '\r' && text_[end + 1] == '\n' ? 2 : 1);
    ++line_;
    tokens.clear();
    size_t i = 0;
    while (i < raw.size()) {
      while (i < raw.size() && std::isspace(static_cast<unsigned char>(raw[i]))) ++i;
      size_t j = i;
      while (j < raw.size() && !std::isspace(static_cast<unsigned char>(raw[j]))) ++j;
      if (j > i) tokens.push_back(raw.substr(i, j - i));
      i = j;
    }
    return true;
  }
  size_t line() const { return line_; }
  size_t remaining() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t line_ = 0;
};

// File text quoted in a message, cut to kMaxQuoted characters: a line with no line breaks (a
// whole frame, a binary file) is not repeated whole.
constexpr size_t kMaxQuoted = 80;
std::string quotedText(std::string_view s) {
  if (s.size() <= kMaxQuoted) return "'" + std::string(s) + "'";
  return "'" + std::string(s.substr(0, kMaxQuoted)) + "...' (" + std::to_string(s.size()) + " characters)";
}

std::string shortNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool parseDouble(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

bool parseChannel(std::string_view s, BvhChannel& c) {
  static constexpr std::string_view kNames[] = {"Xposition", "Yposition", "Zposition",
                                                "Xrotation", "Yrotation", "Zrotation"};
  for (int i = 0; i < 6; ++i) {
    if (iequals(s, kNames[i])) {
      c = static_cast<BvhChannel>(i);
      return true;
    }
  }
  return false;
}

// The frame times a file may state: the rates --fps takes (core/frame_rate.h), 1000 Hz and 1 Hz
// included, with 1 % for a rounded Frame Time (1/1000 written as 0.00099, a 1 Hz clip as 1.01).
// "Frame Time: 1e-9" read as 10^9 Hz and squeezed a 3 s walk into 0.4 microseconds.
constexpr double kFrameTimeSlack = 0.01;
constexpr double kMinFrameTime = (1.0 - kFrameTimeSlack) / kMaxFps;
constexpr double kMaxFrameTime = (1.0 + kFrameTimeSlack) / kMinFps;

class Parser {
 public:
  Parser(std::string_view text, const std::string& name, const BvhLimits& limits)
      : lex_(text), name_(name), limits_(limits) {}

  Result<BvhClip> run() {
    if (auto s = hierarchy(); !s) return Error{s.error()};
    if (auto s = motion(); !s) return Error{s.error()};
    return std::move(clip_);
  }

 private:
  Error fail(const std::string& msg) const {
    return Error{name_ + ":" + std::to_string(lex_.line()) + ": " + msg};
  }

  // Next non-empty line; false at the end of the file.
  bool next() {
    while (lex_.nextLine(tokens_, raw_))
      if (!tokens_.empty()) return true;
    return false;
  }

  Status hierarchy() {
    if (!next()) return Error{name_ + ": empty file (expected HIERARCHY)"};
    if (!iequals(tokens_[0], "HIERARCHY"))
      return fail("expected HIERARCHY, found " + quotedText(tokens_[0]));
    std::vector<int> stack;  // open joints
    bool expectBrace = false;
    bool anyRoot = false;
    while (true) {
      if (!next()) return fail("unexpected end of file in HIERARCHY (missing '}' or MOTION)");
      size_t i = 0;
      while (i < tokens_.size()) {
        const std::string_view tok = tokens_[i];
        if (expectBrace) {
          if (tok != "{") return fail("expected '{' after the joint name, found " + quotedText(tok));
          expectBrace = false;
          ++i;
          continue;
        }
        if (tok == "}") {
          if (stack.empty()) return fail("unmatched '}'");
          stack.pop_back();
          ++i;
          continue;
        }
        if (iequals(tok, "MOTION")) {
          if (!stack.empty()) return fail("MOTION before every joint is closed with '}'");
          if (!anyRoot) return fail("no ROOT joint before MOTION");
          return {};
        }
        const bool isRoot = iequals(tok, "ROOT"), isJoint = iequals(tok, "JOINT");
        const bool isEnd = iequals(tok, "End") && i + 1 < tokens_.size() && iequals(tokens_[i + 1], "Site");
        if (isRoot || isJoint || isEnd) {
          if (auto st = openJoint(i, stack, isRoot, isEnd); !st) return st;
          anyRoot = anyRoot || isRoot;
          expectBrace = true;
          continue;
        }
        if (stack.empty()) return fail("expected ROOT, found " + quotedText(tok));
        Status st = iequals(tok, "OFFSET")     ? readOffset(i, stack.back())
                    : iequals(tok, "CHANNELS") ? readChannels(i, stack.back())
                                               : fail("unexpected " + quotedText(tok) + " in HIERARCHY");
        if (!st) return st;
      }
    }
  }

  // ROOT / JOINT name, or End Site, at tokens_[i]: a new joint under the open one.
  Status openJoint(size_t& i, std::vector<int>& stack, bool isRoot, bool isEnd) {
    const std::string_view tok = tokens_[i];
    if (isRoot && !stack.empty()) return fail("ROOT inside another joint");
    if (!isRoot && stack.empty()) return fail(quotedText(tok) + " outside of any joint");
    if (!isRoot && clip_.joints[static_cast<size_t>(stack.back())].endSite) return fail("a joint inside an End Site");
    if (clip_.joints.size() >= limits_.maxJoints)
      return fail("more than " + std::to_string(limits_.maxJoints) + " joints");
    if (stack.size() >= limits_.maxDepth) return fail("hierarchy deeper than " + std::to_string(limits_.maxDepth));
    BvhJoint j;
    j.parent = stack.empty() ? -1 : stack.back();
    j.firstChannel = clip_.channelCount;
    if (isEnd) {
      j.endSite = true;
      j.name = clip_.joints[static_cast<size_t>(j.parent)].name + "_End";
      i += 2;
    } else {
      // The name is the rest of the line (some exporters put spaces in names), minus a '{'.
      size_t last = tokens_.size();
      if (last > i + 1 && tokens_[last - 1] == "{") --last;
      if (last <= i + 1) return fail(quotedText(tok) + " without a name");
      const char* b = tokens_[i + 1].data();
      const char* e = tokens_[last - 1].data() + tokens_[last - 1].size();
      j.name.assign(b, static_cast<size_t>(e - b));
      i = last;
    }
    stack.push_back(static_cast<int>(clip_.joints.size()));
    clip_.joints.push_back(std::move(j));
    return {};
  }

  // OFFSET x y z at tokens_[i], for the open joint `open`.
  Status readOffset(size_t& i, int open) {
    BvhJoint& cur = clip_.joints[static_cast<size_t>(open)];
    if (tokens_.size() - i < 4) return fail("OFFSET needs 3 numbers");
    for (size_t k = 0; k < 3; ++k)
      if (!parseDouble(tokens_[i + 1 + k], cur.offset[static_cast<int>(k)]))
        return fail("OFFSET value " + quotedText(tokens_[i + 1 + k]) + " is not a finite number");
    i += 4;
    return {};
  }

  // CHANNELS n c1..cn at tokens_[i], for the open joint `open`.
  Status readChannels(size_t& i, int open) {
    BvhJoint& cur = clip_.joints[static_cast<size_t>(open)];
    if (cur.endSite) return fail("CHANNELS inside an End Site");
    if (!cur.channels.empty()) return fail("second CHANNELS line for joint " + quotedText(cur.name));
    // Channels must come before the children so the frame layout is depth-first order.
    if (open != static_cast<int>(clip_.joints.size()) - 1)
      return fail("CHANNELS of joint " + quotedText(cur.name) + " after its children");
    double n = 0;
    if (i + 1 >= tokens_.size() || !parseDouble(tokens_[i + 1], n) || n < 0 || n > 6 || n != std::floor(n))
      return fail("CHANNELS needs a count from 0 to 6");
    const size_t count = static_cast<size_t>(n);
    if (tokens_.size() - i - 2 < count)
      return fail("CHANNELS declares " + std::to_string(count) + " channels but lists " +
                  std::to_string(tokens_.size() - i - 2));
    for (size_t k = 0; k < count; ++k) {
      BvhChannel c;
      if (!parseChannel(tokens_[i + 2 + k], c))
        return fail("unknown channel " + quotedText(tokens_[i + 2 + k]) + " (expected X/Y/Z position or rotation)");
      cur.channels.push_back(c);
    }
    cur.firstChannel = clip_.channelCount;
    clip_.channelCount += static_cast<int>(count);
    i += 2 + count;
    return {};
  }

  // The value of the MOTION header line `key` ("Frames:", "Frame Time:"; any case, any run of
  // spaces between its words, none needed after the colon: "Frames:361" as other readers take
  // it): the rest of the line, trimmed. False when the line is not that header.
  bool header(std::string_view key, std::string_view& value) const {
    const std::string_view line = raw_;
    auto space = [&](size_t k) { return k < line.size() && std::isspace(static_cast<unsigned char>(line[k])); };
    size_t i = 0;
    while (space(i)) ++i;
    for (const char c : key) {
      if (c == ' ') {
        if (!space(i)) return false;
        while (space(i)) ++i;
      } else if (i < line.size() && std::tolower(static_cast<unsigned char>(line[i])) == std::tolower(c)) {
        ++i;
      } else {
        return false;
      }
    }
    while (space(i)) ++i;
    size_t e = line.size();
    while (e > i && space(e - 1)) --e;
    value = line.substr(i, e - i);
    return true;
  }

  Status motion() {
    size_t declared = 0;
    bool haveFrames = false, haveTime = false;
    const size_t perFrame = static_cast<size_t>(clip_.channelCount);
    // The most frames the value limit allows (a frame of no channels still counts as one value).
    const size_t maxFrames = limits_.maxValues / std::max<size_t>(perFrame, 1);
    // "MOTION" may share its line with nothing else; the two header lines follow in any order.
    while (!(haveFrames && haveTime)) {
      if (!next()) return fail("unexpected end of file in MOTION (expected 'Frames:' and 'Frame Time:')");
      std::string_view value;
      if (header("Frames:", value)) {
        double n;
        if (!parseDouble(value, n) || n < 0 || n != std::floor(n))
          return fail("'Frames:' needs a non-negative integer, found " + quotedText(value));
        if (n > static_cast<double>(maxFrames))
          return fail("'Frames: " + std::string(value) + "' is more than this loader accepts: at most " +
                      std::to_string(maxFrames) + " frames of " + std::to_string(perFrame) + " channels (" +
                      std::to_string(limits_.maxValues) + " values)");
        declared = static_cast<size_t>(n);
        haveFrames = true;
      } else if (header("Frame Time:", value)) {
        if (!parseDouble(value, clip_.frameTime) || clip_.frameTime <= 0.0)
          return fail("'Frame Time:' needs a positive number of seconds, found " + quotedText(value));
        if (clip_.frameTime < kMinFrameTime || clip_.frameTime > kMaxFrameTime)
          return fail("'Frame Time: " + std::string(value) + "' is " + shortNumber(1.0 / clip_.frameTime) +
                      " frames per second; this loader accepts " + shortNumber(kMinFps) + " .. " +
                      shortNumber(kMaxFps) + " Hz (Frame Time " + shortNumber(1.0 / kMaxFps) + " .. " +
                      shortNumber(1.0 / kMinFps) + " s)");
        haveTime = true;
      } else {
        return fail("expected 'Frames: N' and 'Frame Time: SECONDS', found " + quotedText(raw_));
      }
    }
    // The claim is only a hint for the reserve, and the text bounds it: every value takes at least
    // two bytes (a digit and a separator), so a 1 KB file that claims 10^8 frames reserves 1 KB.
    clip_.values.reserve(std::min(declared * perFrame, lex_.remaining() / 2 + 1));
    size_t frames = 0;
    while (perFrame > 0 && next()) {
      if (frames == declared) {
        clip_.warnings.push_back(name_ + ":" + std::to_string(lex_.line()) + ": data after the " +
                                 std::to_string(declared) + " declared frames ignored");
        break;
      }
      if (tokens_.size() != perFrame)
        return fail("frame " + std::to_string(frames) + " has " + std::to_string(tokens_.size()) +
                    " values, expected " + std::to_string(perFrame));
      for (const auto& t : tokens_) {
        double v;
        // Frames are stored as float: a finite double beyond float's range would become inf.
        if (!parseDouble(t, v) || !(std::abs(v) <= std::numeric_limits<float>::max()))
          return fail("frame value " + quotedText(t) + " is not a finite number within float range");
        clip_.values.push_back(static_cast<float>(v));
      }
      ++frames;
    }
    // Without channels there is nothing to read per frame; the claim still cannot exceed what a
    // file of this size could have listed (one line per frame).
    if (perFrame == 0) frames = std::min(declared, lex_.remaining() + 1);
    if (frames < declared)
      clip_.warnings.push_back(name_ + ": declares " + std::to_string(declared) + " frames but has " +
                               std::to_string(frames) + "; using those");
    if (frames == 0) return fail("no motion frames");
    clip_.frameCount = frames;
    return {};
  }

  Lexer lex_;
  std::string name_;
  BvhLimits limits_;
  BvhClip clip_;
  std::vector<std::string_view> tokens_;
  std::string_view raw_;
};

glm::dquat axisRotation(int axis, double degrees) {
  glm::dvec3 a(0.0);
  a[axis] = 1.0;
  return glm::angleAxis(glm::radians(degrees), a);
}

}  // namespace

int BvhClip::find(std::string_view name) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return static_cast<int>(i);
  return -1;
}

Result<BvhClip> parseBvh(std::string_view text, const std::string& name, const BvhLimits& limits) {
  // A UTF-8 byte order mark (Windows tools write one) is no part of the first keyword.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return Parser(text, name, limits).run();
}

Result<BvhClip> loadBvh(const std::string& path, const BvhLimits& limits) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return Error{path + ": cannot open the BVH file"};
  f.seekg(0, std::ios::end);
  const auto size = f.tellg();
  f.seekg(0);
  // Every frame value takes at least 2 bytes of text, so a file far beyond the value limit is
  // refused before reading it into memory.
  if (size < 0 || static_cast<size_t>(size) > limits.maxValues * 16)
    return Error{path + ": file too large for a BVH clip"};
  std::string text(static_cast<size_t>(size), '\0');
  f.read(text.data(), size);
  if (!f) return Error{path + ": read failed"};
  return parseBvh(text, path, limits);
}

void bvhGlobals(const BvhClip& clip, std::span<const float> frame, std::vector<BvhGlobal>& out) {
  out.resize(clip.joints.size());
  const bool rest = frame.size() < static_cast<size_t>(clip.channelCount) || clip.channelCount == 0;
  for (size_t j = 0; j < clip.joints.size(); ++j) {
    const BvhJoint& joint = clip.joints[j];
    glm::dvec3 t = joint.offset;
    glm::dquat r(1.0, 0.0, 0.0, 0.0);
    if (!rest) {
      for (size_t c = 0; c < joint.channels.size(); ++c) {
        const double v = frame[static_cast<size_t>(joint.firstChannel) + c];
        const int ch = static_cast<int>(joint.channels[c]);
        if (ch < 3)
          t[ch] += v;
        else
          r = r * axisRotation(ch - 3, v);
      }
    }
    if (joint.parent < 0) {
      out[j].position = t;
      out[j].rotation = r;
    } else {
      const BvhGlobal& p = out[static_cast<size_t>(joint.parent)];
      out[j].position = p.position + p.rotation * t;
      out[j].rotation = glm::normalize(p.rotation * r);
    }
  }
}

void mirrorBvhClip(BvhClip& clip) {
  std::vector<size_t> flip;  // value indices within a frame
  for (auto& j : clip.joints) {
    j.offset.x = -j.offset.x;
    for (size_t c = 0; c < j.channels.size(); ++c)
      if (j.channels[c] == BvhChannel::Xposition || j.channels[c] == BvhChannel::Yrotation ||
          j.channels[c] == BvhChannel::Zrotation)
        flip.push_back(static_cast<size_t>(j.firstChannel) + c);
  }
  const auto n = static_cast<size_t>(clip.channelCount);
  for (size_t f = 0; f < clip.frameCount; ++f)
    for (size_t k : flip) clip.values[f * n + k] = -clip.values[f * n + k];
}

}  // namespace embody::avatar
