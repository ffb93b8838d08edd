// `robotperf completion bash|zsh`: the shell's completion script, made from the commands as they
// are declared, so that it never lists a command or option robotperf does not have. The build
// writes both and installs them (bash-completion's and zsh's folders).
#include <iostream>
#include <map>
#include <sstream>

#include "../parse_errors.hpp"
#include "commands.hpp"

namespace robotperf::cli {

namespace {

// What the completion offers after one command path ("" for robotperf itself, "results list").
struct CompletionEntry {
  std::vector<std::string> words;                           // subcommands and options
  std::map<std::string, std::vector<std::string>> choices;  // option -> its values
  std::vector<std::string> path_options;                    // options that take a file or folder
  std::vector<std::string> positional_choices;              // the values of a positional
  bool takes_benchmark = false;                             // a positional benchmark id
};

bool takes_a_path(const CLI::Option& option) {
  const std::string text = option.get_description();
  for (const char* word : {"folder", "file", "directory", "bag", "keystore"})
    if (text.find(word) != std::string::npos) return true;
  return false;
}

void collect(CLI::App& app, const std::string& path, std::map<std::string, CompletionEntry>& out) {
  CompletionEntry& entry = out[path];
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    entry.words.push_back(sub->get_name());
    collect(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), out);
  }
  for (const CLI::Option* o : app.get_options()) {
    if (o->get_positional()) {
      const auto members = members_in_braces(o->get_type_name());
      entry.positional_choices.insert(entry.positional_choices.end(), members.begin(),
                                      members.end());
      entry.takes_benchmark |= o->get_name() == "id";
      continue;
    }
    for (const std::string& l : o->get_lnames()) {
      const std::string name = "--" + l;
      entry.words.push_back(name);
      if (o->get_items_expected_min() == 0) continue;
      if (auto members = members_in_braces(o->get_type_name()); !members.empty())
        entry.choices[name] = members;
      else if (takes_a_path(*o))
        entry.path_options.push_back(name);
    }
  }
}

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

// How one shell writes what both scripts do.
struct ShellSyntax {
  const char* open;  // before a case pattern: "" in bash, "(" in zsh
  // Completes one of `values` (space-separated words) and returns.
  std::string (*complete_words)(const std::string& values);
  const char* complete_files;  // completes a file name and returns
};

// The case bodies both scripts share: which command path the words so far name (`case
// "$next"`), what an option's value may be (`case "$cmdpath|$prev"`), and what each path offers
// (`case "$cmdpath"`).
void write_command_paths(std::ostream& s, const std::map<std::string, CompletionEntry>& entries,
                         const ShellSyntax& shell) {
  for (const auto& [path, entry] : entries)
    if (!path.empty()) s << "      " << shell.open << "\"" << path << "\") cmdpath=\"$next\" ;;\n";
}

void write_option_values(std::ostream& s, const std::map<std::string, CompletionEntry>& entries,
                         const ShellSyntax& shell) {
  for (const auto& [path, entry] : entries) {
    for (const auto& [option, members] : entry.choices)
      s << "    " << shell.open << "\"" << path << "|" << option << "\") "
        << shell.complete_words(joined(members)) << " ;;\n";
    for (const auto& option : entry.path_options)
      s << "    " << shell.open << "\"" << path << "|" << option << "\") " << shell.complete_files
        << " ;;\n";
  }
}

void write_offers(std::ostream& s, const std::map<std::string, CompletionEntry>& entries,
                  const ShellSyntax& shell) {
  for (const auto& [path, entry] : entries) {
    std::vector<std::string> words = entry.words;
    words.insert(words.end(), entry.positional_choices.begin(), entry.positional_choices.end());
    s << "    " << shell.open << "\"" << path << "\") offer=\"" << joined(words) << "\""
      << (entry.takes_benchmark ? "; ids=1" : "") << " ;;\n";
  }
}

// The loop over the words before the cursor, then the two cases.
void write_cases(std::ostream& s, const std::map<std::string, CompletionEntry>& entries,
                 const ShellSyntax& shell) {
  s << "    case \"$next\" in\n";
  write_command_paths(s, entries, shell);
  s << "    esac\n  done\n  case \"$cmdpath|$prev\" in\n";
  write_option_values(s, entries, shell);
  s << "  esac\n  case \"$cmdpath\" in\n";
  write_offers(s, entries, shell);
  s << "  esac\n";
}

const ShellSyntax kBash{"",
                        [](const std::string& values) {
                          return "COMPREPLY=($(compgen -W \"" + values + "\" -- \"$cur\")); return";
                        },
                        "COMPREPLY=($(compgen -f -- \"$cur\")); return"};

const ShellSyntax kZsh{
    "(", [](const std::string& values) { return "compadd -- " + values + "; return"; },
    "_files; return"};

std::string bash_script(const std::map<std::string, CompletionEntry>& entries) {
  std::ostringstream s;
  s << "# bash completion for robotperf (made by `robotperf completion bash`)\n"
       "_robotperf() {\n"
       "  local cur=\"${COMP_WORDS[COMP_CWORD]}\" prev=\"${COMP_WORDS[COMP_CWORD-1]}\"\n"
       "  local cmdpath=\"\" next w i offer=\"\" ids=0\n"
       "  for ((i = 1; i < COMP_CWORD; i++)); do\n"
       "    w=\"${COMP_WORDS[i]}\"; next=\"${cmdpath:+$cmdpath }$w\"\n";
  write_cases(s, entries, kBash);
  s << "  if [[ $ids == 1 && $cur != -* ]]; then\n"
       "    offer=\"$offer $(\"${COMP_WORDS[0]}\" list --ids 2>/dev/null)\"\n"
       "  fi\n"
       "  COMPREPLY=($(compgen -W \"$offer\" -- \"$cur\"))\n"
       "}\n"
       "complete -F _robotperf robotperf\n";
  return s.str();
}

std::string zsh_script(const std::map<std::string, CompletionEntry>& entries) {
  std::ostringstream s;
  // zsh's `path` is PATH as an array and `words` the command line: neither is a name of ours.
  s << "#compdef robotperf\n"
       "# zsh completion for robotperf (made by `robotperf completion zsh`)\n"
       "_robotperf() {\n"
       "  local cmdpath=\"\" next w i offer=\"\" ids=0 prev=\"${words[CURRENT-1]}\"\n"
       "  for ((i = 2; i < CURRENT; i++)); do\n"
       "    w=\"${words[i]}\"; next=\"${cmdpath:+$cmdpath }$w\"\n";
  write_cases(s, entries, kZsh);
  s << "  local -a offered=(${=offer})\n"
       "  if [[ $ids == 1 && ${words[CURRENT]} != -* ]]; then\n"
       "    offered+=(${(f)\"$(${words[1]} list --ids 2>/dev/null)\"})\n"
       "  fi\n"
       "  compadd -- $offered\n"
       "}\n"
       "_robotperf \"$@\"\n";
  return s.str();
}

class CompletionCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    root_ = &app;
    auto* command = app.add_subcommand(
        "completion", "print the bash or zsh completion script (installed with robotperf)");
    command->add_option("shell", shell_, "bash or zsh")
        ->required()
        ->check(CLI::IsMember({"bash", "zsh"}));
    command->footer(
        "Examples: source <(robotperf completion bash)\n"
        "          robotperf completion zsh > ~/.zfunc/_robotperf");
    return command;
  }

  int run(const Context&) override {
    std::map<std::string, CompletionEntry> entries;
    collect(*root_, "", entries);
    std::cout << (shell_ == "bash" ? bash_script(entries) : zsh_script(entries));
    return 0;
  }

 private:
  CLI::App* root_ = nullptr;
  std::string shell_;
};

}  // namespace

std::unique_ptr<Command> completion_command() {
  return std::make_unique<CompletionCommand>();
}

}  // namespace robotperf::cli
