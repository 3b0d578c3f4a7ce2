#pragma once
// The embody CLI: each subcommand lives in its own app/cmd_*.cpp and registers itself with
// EMBODY_COMMAND, so adding a command touches no shared file.
#include <span>
#include <string>
#include <vector>

namespace embody::app {

using Argv = std::span<const std::string>;
using CommandFn = int (*)(Argv args);  // args exclude the command name; returns the exit code

struct Command {
  const char* name;
  const char* summary;
  CommandFn run;
};

bool registerCommand(const Command& command);
const std::vector<Command>& commands();

}  // namespace embody::app

#define EMBODY_CLI_CONCAT2(a, b) a##b
#define EMBODY_CLI_CONCAT(a, b) EMBODY_CLI_CONCAT2(a, b)
#define EMBODY_COMMAND(name, summary, fn)                                                   \
  [[maybe_unused]] static const bool EMBODY_CLI_CONCAT(embody_command_registered_, __LINE__) = \
      ::embody::app::registerCommand({name, summary, fn})
