// `lambert options`: every option of every command from the CLI's own registrations, the
// declarations (pipeline/option_specs.hpp) and the table of which choice reads what
// (pipeline/option_scope.hpp). `--markdown` prints the reference of docs/options.md, which
// scripts/check_docs_options.sh keeps current.

#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "apps/commands.hpp"
#include "pipeline/option_scope.hpp"
#include "pipeline/option_specs.hpp"

namespace lambert {
namespace {

// One option as a command registers it.
struct OptionRow {
  std::string names;    // "-j, --threads"
  std::string accepts;  // "an integer in [1, 1048576]", "flag", "FILE", ...
  std::string default_text;
  std::string read_by;
  std::string description;
  std::vector<std::string> commands;
};

std::string accepts_of(const CLI::Option& o, const std::string& name) {
  for (const OptionSpec& s : option_specs())
    if (s.name == name) return accepted_text(s);
  std::string t = o.get_type_name();  // "INT:INT in [1 - 1024]", "TEXT", "" for a flag
  const auto colon = t.find(':');
  if (colon != std::string::npos) t = t.substr(colon + 1);
  return t.empty() ? "flag" : t;
}

std::string read_by(const std::string& name) {
  for (const OptionScope& row : option_scopes())
    if (row.option == name) return row.reader;
  return "";
}

std::string cell(std::string text) {  // a Markdown table cell
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

CLI::App* add_options_command(CLI::App& app, OptionsOptions& opts) {
  auto* cmd = app.add_subcommand(
      "options", "List every option of every command: values, default, what reads it");
  cmd->add_flag("--markdown", opts.markdown,
                "Print the reference table of docs/options.md (Markdown)");
  opts.app = &app;
  return cmd;
}

int run_options(const OptionsOptions& opts) {
  // Rows keyed by option and by everything a reader sees, so that an option registered alike
  // by several commands is one row listing them.
  std::map<std::tuple<std::string, std::string, std::string, std::string>, OptionRow> rows;
  for (const CLI::App* cmd : opts.app->get_subcommands([](const CLI::App*) { return true; })) {
    if (cmd->get_name() == "options") continue;
    for (const CLI::Option* o : cmd->get_options()) {
      if (o->get_lnames().empty() || o->get_lnames().front() == "help") continue;
      const std::string name = "--" + o->get_lnames().front();
      std::string names;
      for (const auto& s : o->get_snames()) names += "-" + s + ", ";
      for (const auto& l : o->get_lnames()) names += "--" + l + ", ";
      names.resize(names.size() - 2);
      const std::string accepts = accepts_of(*o, name);
      const auto key =
          std::make_tuple(name, names + accepts, o->get_default_str(), o->get_description());
      OptionRow& row = rows[key];
      if (row.commands.empty())
        row = {names, accepts, o->get_default_str(), read_by(name), o->get_description(), {}};
      row.commands.push_back(cmd->get_name());
    }
  }
  if (opts.markdown) {
    std::printf("| option | commands | accepts | default | read by | description |\n");
    std::printf("|---|---|---|---|---|---|\n");
  }
  for (const auto& [key, r] : rows) {
    std::string commands;
    for (const auto& c : r.commands) commands += (commands.empty() ? "" : ", ") + c;
    if (opts.markdown)
      std::printf("| `%s` | %s | %s | %s | %s | %s |\n", r.names.c_str(), cell(commands).c_str(),
                  cell(r.accepts).c_str(), cell(r.default_text).c_str(),
                  cell(r.read_by.empty() ? "every choice" : r.read_by).c_str(),
                  cell(r.description).c_str());
    else
      std::printf("%s (%s): %s; default %s; read by %s. %s\n", r.names.c_str(), commands.c_str(),
                  r.accepts.c_str(), r.default_text.empty() ? "none" : r.default_text.c_str(),
                  r.read_by.empty() ? "every choice" : r.read_by.c_str(), r.description.c_str());
  }
  return 0;
}

}  // namespace lambert
