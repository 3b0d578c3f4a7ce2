#include "app/args.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace embody::app {

Args::Args(std::string usagePrefix, std::string summary)
    : prefix_(std::move(usagePrefix)), summary_(std::move(summary)) {}

Args& Args::option(const std::string& name, const std::string& valueName, const std::string& help,
                   std::optional<std::string> defaultValue) {
  options_.push_back({name, valueName, help, false, std::move(defaultValue)});
  return *this;
}

Args& Args::flag(const std::string& name, const std::string& help) {
  options_.push_back({name, "", help, true, std::nullopt});
  return *this;
}

Args& Args::positional(const std::string& name, const std::string& help, bool required) {
  positionals_.push_back({name, help, required});
  return *this;
}

const Args::Spec* Args::find(const std::string& name) const {
  for (const auto& s : options_)
    if (s.name == name) return &s;
  return nullptr;
}

std::string Args::usage() const {
  std::ostringstream o;
  o << "usage: " << prefix_;
  for (const auto& p : positionals_) o << (p.required ? " " : " [") << p.name << (p.required ? "" : "]");
  if (!options_.empty()) o << " [options]";
  o << "\n\n" << summary_ << "\n";
  if (!positionals_.empty()) {
    o << "\narguments:\n";
    for (const auto& p : positionals_) o << "  " << p.name << "\n      " << p.help << "\n";
  }
  o << "\noptions:\n";
  for (const auto& s : options_) {
    o << "  --" << s.name << (s.isFlag ? "" : " " + s.valueName) << "\n      " << s.help;
    if (s.defaultValue) o << " (default: " << *s.defaultValue << ")";
    o << "\n";
  }
  o << "  --help\n      show this help\n";
  return o.str();
}

Args::Outcome Args::parse(Argv argv) {
  values_.clear();
  size_t nextPositional = 0;
  // One line, as for every bad value (app/job_options.h: usageError); --help has the rest.
  auto fail = [&](const std::string& msg) {
    std::fprintf(stderr, "error: %s (see '%s --help')\n", msg.c_str(), prefix_.c_str());
    return Outcome::Error;
  };
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(usage().c_str(), stdout);
      return Outcome::Help;
    }
    if (a.rfind("--", 0) == 0 && a.size() > 2) {
      std::string name(a.begin() + 2, a.end());
      std::string value;
      bool inlineValue = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        inlineValue = true;
      }
      const Spec* s = find(name);
      if (!s) return fail("unknown option --" + name);
      if (s->isFlag) {
        if (inlineValue) return fail("--" + name + " takes no value");
        values_[name] = "1";
      } else {
        if (!inlineValue) {
          if (i + 1 >= argv.size()) return fail("--" + name + " needs a value (" + s->valueName + ")");
          value = argv[++i];
        }
        values_[name] = value;
      }
      continue;
    }
    if (nextPositional >= positionals_.size()) return fail("unexpected argument '" + a + "'");
    values_[positionals_[nextPositional++].name] = a;
  }
  for (size_t p = nextPositional; p < positionals_.size(); ++p)
    if (positionals_[p].required) return fail("missing argument " + positionals_[p].name);
  for (const auto& s : options_)
    if (s.defaultValue && !values_.count(s.name)) values_[s.name] = *s.defaultValue;
  return Outcome::Ok;
}

bool Args::has(const std::string& name) const { return values_.count(name) != 0; }

std::string Args::get(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::string() : it->second;
}

namespace {
// The whole of `v` as a finite number.
bool parseFinite(const std::string& v, double& d) {
  size_t used = 0;
  try {
    d = std::stod(v, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  return !v.empty() && used == v.size() && std::isfinite(d);
}
}  // namespace

double Args::number(const std::string& name) const {
  const std::string v = get(name);
  double d = 0;
  if (!parseFinite(v, d)) throw std::invalid_argument("--" + name + " expects a finite number, got '" + v + "'");
  return d;
}

std::vector<double> Args::numbers(const std::string& name) const {
  const std::string v = get(name);
  std::vector<double> out;
  for (size_t at = 0; at <= v.size();) {
    const size_t comma = std::min(v.find(',', at), v.size());
    double d = 0;
    if (!parseFinite(v.substr(at, comma - at), d))
      throw std::invalid_argument("--" + name + " expects finite numbers separated by commas, got '" + v + "'");
    out.push_back(d);
    at = comma + 1;
  }
  return out;
}

int Args::integer(const std::string& name) const {
  const std::string v = get(name);
  size_t used = 0;
  long long n = 0;
  try {
    n = std::stoll(v, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != v.size() || v.empty()) throw std::invalid_argument("--" + name + " expects an integer, got '" + v + "'");
  if (n < -2147483647LL || n > 2147483647LL)  // (std::stoll's own overflow is caught above as not a number)
    throw std::invalid_argument("--" + name + " is out of range: '" + v + "'");
  return static_cast<int>(n);
}

int usageError(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return 2;
}

int runtimeError(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return 1;
}

}  // namespace embody::app
