// embody: the command-line front end. Each subcommand registers itself (app/cmd_*.cpp).
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "app/cli.h"

namespace embody::app {

std::vector<Command>& registry() {
  static std::vector<Command> r;
  return r;
}
bool registerCommand(const Command& command) {
  registry().push_back(command);
  return true;
}
const std::vector<Command>& commands() { return registry(); }

}  // namespace embody::app

namespace {

void printUsage(std::FILE* to) {
  std::fprintf(to,
               "usage: embody <command> [options]\n\n"
               "Embody puts a person inside a VR avatar: tracking -> prioritized IK with a coupled\n"
               "spine -> skinning -> rendering (headless, desktop mirror or OpenXR).\n\ncommands:\n");
  auto cmds = embody::app::commands();
  std::sort(cmds.begin(), cmds.end(), [](const auto& a, const auto& b) { return std::string(a.name) < b.name; });
  for (const auto& c : cmds) std::fprintf(to, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(to, "\nRun 'embody <command> --help' for a command's options.\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    printUsage(args.empty() ? stderr : stdout);
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--version") {
    std::printf("embody %s\n", EMBODY_VERSION);
    return 0;
  }
  for (const auto& c : embody::app::commands()) {
    if (args[0] != c.name) continue;
    try {
      return c.run(std::span<const std::string>(args).subspan(1));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: embody %s: %s\n", c.name, e.what());
      return 1;
    }
  }
  std::fprintf(stderr, "error: unknown command '%s' (see 'embody --help')\n", args[0].c_str());
  return 2;
}
