// `robotperf help [COMMAND...]`: a command's help, as `robotperf COMMAND... --help` prints it.
#include <iostream>
#include <stdexcept>

#include "../parse_errors.hpp"
#include "commands.hpp"

namespace robotperf::cli {

namespace {

class HelpCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    root_ = &app;
    auto* command = app.add_subcommand("help", "show a command's help (robotperf help run)");
    command->add_option("command", words_, "the command, and its subcommand if it has them");
    command->footer("Examples: robotperf help run\n          robotperf help results list");
    return command;
  }

  int run(const Context&) override {
    CLI::App* at = root_;
    for (const std::string& word : words_) at = &subcommand_of(*at, word);
    // Not App::help(), which prints the help of the command parsed (help itself) instead.
    std::cout << at->get_formatter()->make_help(at, command_path(at), CLI::AppFormatMode::Normal);
    return 0;
  }

 private:
  CLI::App* root_ = nullptr;
  std::vector<std::string> words_;
};

}  // namespace

std::unique_ptr<Command> help_command() {
  return std::make_unique<HelpCommand>();
}

}  // namespace robotperf::cli
