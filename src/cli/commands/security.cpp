// `robotperf security init DIR`: a DDS Security keystore in the SROS2 layout.
#include "robotperf/rmw/security.hpp"

#include <iostream>

#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"

namespace robotperf::cli {

namespace {

class SecurityCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand("security", "DDS Security keystores (SROS2 layout)");
    command->require_subcommand(1);
    command->footer(
        "Example: robotperf security init keystore && robotperf run n4 --security keystore");
    auto* init = command->add_subcommand(
        "init",
        "make a keystore: a CA, and per enclave a certificate, key, and signed governance and "
        "permissions (adds missing enclaves to an existing keystore)");
    init->add_option("dir", dir_, "the keystore folder")->required();
    init->add_option("--enclave", enclaves_,
                     "an enclave to make, e.g. /my_robot/camera (default: /robotperf); repeatable")
        ->type_name("NAME");
    init->add_flag("--renew", renew_,
                   "replace the keystore, damaged or not, with a new one: a new CA and every "
                   "enclave it held (plus --enclave ones), signed by it");
    init->footer(
        "Examples: robotperf security init keys --enclave /robotperf\n"
        "          robotperf security init keys --renew");
    return command;
  }

  int run(const Context&) override {
    // Named absolutely before it is made, whatever becomes of the current folder.
    const fs::path keystore = fs::absolute(dir_);
    if (renew_) {
      enclaves_ = rmw::renew_keystore(keystore, enclaves_);
    } else {
      if (enclaves_.empty()) enclaves_.push_back(rmw::kDefaultEnclave);
      rmw::create_keystore(keystore, enclaves_);
    }
    fs::path shown = keystore.lexically_normal();
    if (!shown.has_filename()) shown = shown.parent_path();  // "dir/." is "dir/"
    std::cout << "keystore: " << shown.string() << "\n";
    for (const auto& enclave : enclaves_) {
      std::cout << "  enclave " << enclave << ": "
                << rmw::describe(rmw::enclave_files(keystore, enclave)) << "\n";
    }
    std::cout << "use it with: robotperf run n4 --netns --security " << dir_ << "\n";
    return kExitOk;
  }

 private:
  std::string dir_;
  std::vector<std::string> enclaves_;
  bool renew_ = false;
};

}  // namespace

std::unique_ptr<Command> security_command() {
  return std::make_unique<SecurityCommand>();
}

}  // namespace robotperf::cli
