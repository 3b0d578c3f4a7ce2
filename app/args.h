#pragma once
// A small declarative argument parser shared by every subcommand, so options look and fail the
// same way everywhere: `--name VALUE`, `--name=VALUE`, boolean `--flag`, positionals, `--help`.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/cli.h"

namespace embody::app {

class Args {
 public:
  Args(std::string usagePrefix, std::string summary);

  Args& option(const std::string& name, const std::string& valueName, const std::string& help,
               std::optional<std::string> defaultValue = std::nullopt);
  Args& flag(const std::string& name, const std::string& help);
  Args& positional(const std::string& name, const std::string& help, bool required = true);

  enum class Outcome { Ok, Help, Error };
  // Parses; on --help prints the usage to stdout, on an error one line naming the option to stderr.
  Outcome parse(Argv argv);
  // Exit code for a non-Ok outcome: 0 after --help, 2 after a usage error.
  static int exitCode(Outcome o) { return o == Outcome::Help ? 0 : 2; }

  bool has(const std::string& name) const;  // given on the command line (or has a default)
  std::string get(const std::string& name) const;  // "" when absent
  double number(const std::string& name) const;    // throws std::invalid_argument with a clear message
  std::vector<double> numbers(const std::string& name) const;  // "60,90,120"; throws as number()
  int integer(const std::string& name) const;
  std::string usage() const;

 private:
  struct Spec {
    std::string name, valueName, help;
    bool isFlag = false;
    std::optional<std::string> defaultValue;
  };
  struct Positional {
    std::string name, help;
    bool required = true;
  };
  std::string prefix_, summary_;
  std::vector<Spec> options_;
  std::vector<Positional> positionals_;
  std::map<std::string, std::string> values_;
  const Spec* find(const std::string& name) const;
};

// Print "error: MESSAGE" on one line and return the exit code: 2 for a bad option value (a
// usage error), 1 for a runtime error (a broken file, no device, a failed write).
int usageError(const std::string& message);
int runtimeError(const std::string& message);

}  // namespace embody::app
