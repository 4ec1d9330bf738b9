// Usage errors: what was mistyped on the command line, said with the word and a near name.
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/quoted.h"
#include "polrig/suggest.h"

namespace polrig::cli {
namespace {

// "polrig study: " for a subcommand; nothing for the top level (main says "polrig: error: ").
std::string where(const CLI::App* app) {
  std::string name;
  for (; app->get_parent(); app = app->get_parent()) name = app->get_name() + (name.empty() ? "" : " " + name);
  return name.empty() ? name : "polrig " + name + ": ";
}

std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
  return names;
}

// Every long option a command takes, its own and its parents' ("--threads" is the top level's).
std::vector<std::string> option_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* a = &app; a; a = a->get_parent())
    for (const CLI::Option* o : a->get_options())
      for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
  return names;
}

const CLI::Option* find_option(const CLI::App& app, const std::string& name) {
  for (const CLI::App* a = &app; a; a = a->get_parent())
    if (const CLI::Option* o = a->get_option_no_throw(name)) return o;
  return nullptr;
}

const CLI::App* find_subcommand(const CLI::App& app, const std::string& name) {
  for (const CLI::App* sub : app.get_subcommands({}))
    if (sub->check_name(name)) return sub;
  return nullptr;
}

bool takes_positionals(const CLI::App& app) {
  for (const CLI::Option* o : app.get_options())
    if (o->get_positional()) return true;
  return false;
}

// The first word that names no command or option where it stands, with a near name if any.
std::optional<std::string> unknown_word(const CLI::App& top, int argc, char** argv) {
  const CLI::App* app = &top;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--") return std::nullopt;
    if (word.rfind("--", 0) == 0) {
      const std::string name = word.substr(0, word.find('='));
      const CLI::Option* o = find_option(*app, name);
      if (!o)
        return fmt::format("{}unknown option '{}'{}", where(app), quoted_value(name),
                           did_you_mean(name, option_names(*app)));
      if (o->get_type_size_max() > 0 && name.size() == word.size()) ++i;  // its value
    } else if (word.size() > 1 && word[0] == '-') {
      if (const CLI::Option* o = find_option(*app, word.substr(0, 2));
          o && o->get_type_size_max() > 0 && word.size() == 2)
        ++i;
    } else if (const CLI::App* sub = find_subcommand(*app, word)) {
      app = sub;
    } else if (!app->get_subcommands({}).empty() && !takes_positionals(*app)) {
      return fmt::format("{}unknown command '{}'{}; the commands: {}", where(app), quoted_value(word),
                         did_you_mean(word, subcommand_names(*app)),
                         fmt::join(subcommand_names(*app), ", "));
    }
  }
  return std::nullopt;
}

}  // namespace

std::string usage_error(const CLI::App& app, int argc, char** argv, const CLI::ParseError& e) {
  if (const std::optional<std::string> word = unknown_word(app, argc, argv)) return *word;
  return e.what();
}

}  // namespace polrig::cli
