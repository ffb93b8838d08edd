#include "parse_errors.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "robotperf/harness/suggestions.hpp"

namespace robotperf::cli {
namespace {

CLI::App* subcommand_named(CLI::App* app, const std::string& name) {
  const auto found = app->get_subcommands([&](CLI::App* s) { return s->check_name(name); });
  return found.empty() ? nullptr : found.front();
}

std::vector<std::string> subcommand_names(CLI::App* app) {
  std::vector<std::string> names;
  for (CLI::App* s : app->get_subcommands([](CLI::App*) { return true; }))
    names.push_back(s->get_name());
  return names;
}

bool takes_positionals(CLI::App* app) {
  return !app->get_options([](CLI::Option* o) { return o->get_positional(); }).empty();
}

// The option `name` ("--rate", "-h") as `app` reads it: its own, or a parent's it falls through
// to.
const CLI::Option* option_named(CLI::App* app, const std::string& name) {
  for (CLI::App* at = app; at != nullptr; at = at->get_parent()) {
    if (const CLI::Option* o = at->get_option_no_throw(name)) return o;
  }
  return nullptr;
}

std::vector<std::string> option_names(CLI::App* app) {
  std::vector<std::string> names;
  for (CLI::App* at = app; at != nullptr; at = at->get_parent()) {
    for (const CLI::Option* o : at->get_options())
      for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
  }
  return names;
}

std::string unknown_command(CLI::App& app, const std::string& word) {
  return "unknown command '" + word + "'" + harness::did_you_mean(word, subcommand_names(&app)) +
         " (" + command_path(&app) + " --help lists the commands)";
}

// "VALUE not in {A,B,C}" (CLI11's IsMember), with the member VALUE is a typo of.
std::string with_member_suggestion(const std::string& message) {
  const auto not_in = message.find(" not in {");
  const auto close = message.find('}', not_in);
  if (not_in == std::string::npos || close == std::string::npos) return message;
  const auto colon = message.rfind(": ", not_in);
  const auto value_start = colon == std::string::npos ? 0 : colon + 2;
  const std::string value = message.substr(value_start, not_in - value_start);
  return message.substr(0, close + 1) +
         harness::did_you_mean(value, members_in_braces(message.substr(not_in))) +
         message.substr(close + 1);
}

// The first verb or option of `args` that does not exist, said with its nearest; "" when every
// one exists (the error is of another kind). `at` ends at the deepest command `args` name.
std::string unknown_word(CLI::App*& at, const std::vector<std::string>& args) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& word = args[i];
    if (word == "--") break;
    if (word.size() > 1 && word[0] == '-') {
      const std::string name = word.substr(0, word.find('='));
      const CLI::Option* option = option_named(at, name);
      if (option == nullptr) {
        return "unknown option " + name + " for '" + command_path(at) + "'" +
               harness::did_you_mean(name, option_names(at)) + " (" + command_path(at) +
               " --help lists them)";
      }
      if (word.find('=') == std::string::npos && option->get_items_expected_min() > 0) ++i;
      continue;
    }
    if (CLI::App* sub = subcommand_named(at, word)) {
      at = sub;
      continue;
    }
    if (!subcommand_names(at).empty() && !takes_positionals(at)) return unknown_command(*at, word);
  }
  return "";
}

}  // namespace

std::vector<std::string> members_in_braces(const std::string& text) {
  std::vector<std::string> members;
  const auto open = text.find('{');
  const auto close = text.find('}', open);
  if (open == std::string::npos || close == std::string::npos) return members;
  std::istringstream items(text.substr(open + 1, close - open - 1));
  for (std::string item; std::getline(items, item, ',');) members.push_back(item);
  return members;
}

std::string command_path(const CLI::App* app) {
  std::string path;
  for (; app != nullptr; app = app->get_parent()) {
    const std::string name = app->get_parent() == nullptr ? "robotperf" : app->get_name();
    path = path.empty() ? name : name + " " + path;
  }
  return path;
}

std::string parse_error_line(CLI::App& app, const std::vector<std::string>& args,
                             const CLI::ParseError& error) {
  CLI::App* at = &app;
  const std::string unknown = unknown_word(at, args);
  if (!unknown.empty()) return unknown;
  return with_member_suggestion(error.what()) + " (see " + command_path(at) + " --help)";
}

CLI::App& subcommand_of(CLI::App& app, const std::string& name) {
  if (CLI::App* sub = subcommand_named(&app, name)) return *sub;
  throw std::invalid_argument(unknown_command(app, name));
}

}  // namespace robotperf::cli
