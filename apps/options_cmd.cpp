// `lambert options`: every option of every command, from the declarations
// (pipeline/option_specs.hpp) of the options each command registers. `--markdown` prints the
// reference of docs/options.md, which scripts/check_docs_options.sh keeps current.

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "apps/commands.hpp"
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

std::string cell(std::string text) {  // a Markdown table cell
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

CLI::App* add_options_command(CLI::App& app, OptionsOptions& opts) {
  auto* cmd = app.add_subcommand(
      "options", "List every option of every command: values, default, what reads it");
  add_declared(cmd, "--markdown", opts.markdown);
  opts.app = &app;
  return cmd;
}

int run_options(const OptionsOptions& opts) {
  // Rows keyed by the option's group (in table order), then by option and everything a reader
  // sees, so that an option registered alike by several commands is one row listing them.
  std::vector<std::string> groups;
  for (const OptionSpec& s : option_specs())
    if (std::find(groups.begin(), groups.end(), s.group) == groups.end()) groups.push_back(s.group);
  std::map<std::tuple<std::size_t, std::string, std::string, std::string, std::string>, OptionRow>
      rows;
  for (const CLI::App* cmd : opts.app->get_subcommands([](const CLI::App*) { return true; })) {
    if (cmd->get_name() == "options") continue;
    for (const CLI::Option* o : cmd->get_options()) {
      if (o->get_lnames().empty() || o->get_lnames().front() == "help") continue;
      const std::string name = "--" + o->get_lnames().front();
      std::string names;
      for (const auto& s : o->get_snames()) names += "-" + s + ", ";
      for (const auto& l : o->get_lnames()) names += "--" + l + ", ";
      names.resize(names.size() - 2);
      const OptionSpec& spec = declaration(cmd, name);
      const std::string accepts = accepted_text(spec);
      const std::size_t group =
          std::find(groups.begin(), groups.end(), spec.group) - groups.begin();
      const auto key = std::make_tuple(group, name, names + accepts, spec.default_text, spec.doc);
      OptionRow& row = rows[key];
      if (row.commands.empty())
        row = {names, accepts, spec.default_text, reader_text(spec), spec.doc, {}};
      row.commands.push_back(cmd->get_name());
    }
  }
  std::size_t group = groups.size();
  for (const auto& [key, r] : rows) {
    if (std::get<0>(key) != group) {  // a new group: its heading (and table head)
      group = std::get<0>(key);
      if (opts.markdown)
        std::printf(
            "%s### %s\n\n| option | commands | accepts | default | read by | "
            "description |\n|---|---|---|---|---|---|\n",
            group == 0 ? "" : "\n", groups[group].c_str());
      else
        std::printf("%s%s:\n", group == 0 ? "" : "\n", groups[group].c_str());
    }
    std::string commands;
    for (const auto& c : r.commands) commands += (commands.empty() ? "" : ", ") + c;
    if (opts.markdown)
      std::printf("| `%s` | %s | %s | %s | %s | %s |\n", r.names.c_str(), cell(commands).c_str(),
                  cell(r.accepts).c_str(), cell(r.default_text).c_str(), cell(r.read_by).c_str(),
                  cell(r.description).c_str());
    else
      std::printf("%s (%s): %s; default %s; read by %s. %s\n", r.names.c_str(), commands.c_str(),
                  r.accepts.c_str(), r.default_text.empty() ? "none" : r.default_text.c_str(),
                  r.read_by.c_str(), r.description.c_str());
  }
  return 0;
}

}  // namespace lambert
