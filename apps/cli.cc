// The `candi` command line: the one translation unit with CLI11 (its headers are heavy). It turns
// the groups' declarations (apps/cli.h) into CLI11's, lists the commands in groups along a
// user's path, takes the global flags (-q, -v) before or after the command, and names the option
// behind an options struct's invalid value.
#include "apps/cli.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.h"
#include "apps/logging.h"
#include "core/progress.h"
#include "core/version.h"

namespace candi::apps {

namespace {

CLI::App* AppOf(void* app) { return static_cast<CLI::App*>(app); }
CLI::Option* OptionOf(void* option) { return static_cast<CLI::Option*>(option); }

// `candi --help` lists the commands in groups along a user's path, not alphabetically. CLI11 prints
// the groups in the order their first command was added and a group's commands in the order they
// were added, so the groups add them in this order; GroupCommands checks that they did.
const std::vector<std::pair<std::string, std::vector<std::string>>>& CommandGroups() {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> groups = {
      {"Inspect and convert", {"info", "convert", "compare"}},
      {"Digitize", {"sfm", "dense", "georef", "register", "register-scans", "clean", "colorcorrect", "foundation", "relief"}},
      {"Assemble", {"build", "pack", "export"}},
      {"Look", {"render", "view", "publish", "section"}},
      {"Other", {"opacity", "demo", "campaign", "bench"}},
  };
  return groups;
}

// Puts every top-level command in its group; a command missing from CommandGroups(), or added out
// of its order, is a programming error (caught by any test that runs candi).
void GroupCommands(CLI::App& app) {
  std::vector<std::string> expected;
  for (const auto& [group, names] : CommandGroups()) {
    for (const std::string& name : names) {
      app.get_subcommand(name)->group(group);
      expected.push_back(name);
    }
  }
  std::vector<std::string> added;
  for (const CLI::App* c : app.get_subcommands({})) added.push_back(c->get_name());
  if (added != expected) {
    throw std::logic_error("cli.cc: the commands are not added in the order of CommandGroups(), "
                           "or one is missing from it");
  }
}

// -q and -v on every command too, so that they work after it (`candi render -q ...`).
void AddGlobalFlags(CLI::App& app, int& verbose, bool& quiet) {
  for (CLI::App* c : app.get_subcommands({})) {
    c->add_flag("-v,--verbose", verbose, "More log output (debug)");
    c->add_flag("-q,--quiet", quiet, "Only warnings and errors");
    AddGlobalFlags(*c, verbose, quiet);
  }
}

}  // namespace

Arg& Arg::Required() {
  OptionOf(option_)->required();
  return *this;
}
Arg& Arg::Range(int lo, int hi) {
  OptionOf(option_)->check(CLI::Range(lo, hi));
  return *this;
}
Arg& Arg::Range(double lo, double hi) {
  OptionOf(option_)->check(CLI::Range(lo, hi));
  return *this;
}
Arg& Arg::OneOf(const std::vector<std::string>& values) {
  OptionOf(option_)->check(CLI::IsMember(values));
  return *this;
}
Arg& Arg::Positive() {
  OptionOf(option_)->check(CLI::PositiveNumber);
  return *this;
}
Arg& Arg::NonNegative() {
  OptionOf(option_)->check(CLI::NonNegativeNumber);
  return *this;
}
Arg& Arg::Excludes(const Arg& other) {
  OptionOf(option_)->excludes(OptionOf(other.option_));
  return *this;
}
Arg& Arg::Needs(const Arg& other) {
  OptionOf(option_)->needs(OptionOf(other.option_));
  return *this;
}
Arg& Arg::Delimiter(char separator) {
  OptionOf(option_)->delimiter(separator);
  return *this;
}
Arg& Arg::Repeatable() {
  OptionOf(option_)->expected(1)->take_all();
  return *this;
}
Arg& Arg::OnGiven(std::function<void()> given) {
  OptionOf(option_)->each([given](const std::string&) { given(); });
  return *this;
}

Command Command::Add(const std::string& name, const std::string& description) {
  return Command(AppOf(app_)->add_subcommand(name, description), run_, kept_);
}
Command Command::Find(const std::string& name) { return Command(AppOf(app_)->get_subcommand(name), run_, kept_); }

Arg Command::Option(const std::string& names, std::string& value, const std::string& help) {
  return Arg(AppOf(app_)->add_option(names, value, help));
}
Arg Command::Option(const std::string& names, int& value, const std::string& help) {
  return Arg(AppOf(app_)->add_option(names, value, help));
}
Arg Command::Option(const std::string& names, double& value, const std::string& help) {
  return Arg(AppOf(app_)->add_option(names, value, help));
}
Arg Command::Option(const std::string& names, unsigned long& value, const std::string& help) {  // NOLINT
  return Arg(AppOf(app_)->add_option(names, value, help));
}
Arg Command::Option(const std::string& names, unsigned long long& value, const std::string& help) {  // NOLINT
  return Arg(AppOf(app_)->add_option(names, value, help));
}
Arg Command::Option(const std::string& names, std::vector<std::string>& values, const std::string& help) {
  return Arg(AppOf(app_)->add_option(names, values, help));
}
Arg Command::Option(const std::string& names, std::vector<double>& values, const std::string& help) {
  return Arg(AppOf(app_)->add_option(names, values, help));
}
Arg Command::Flag(const std::string& names, bool& value, const std::string& help) {
  return Arg(AppOf(app_)->add_flag(names, value, help));
}
Arg Command::FlagOff(const std::string& names, bool& value, const std::string& help) {
  return Arg(AppOf(app_)->add_flag_callback(names, [&value] { value = false; }, help));
}
Arg Command::ChoiceIndex(const std::string& names, const std::vector<std::string>& keys,
                         std::function<void(size_t)> set, const std::string& help) {
  // The option's text lives as long as the command line; set() turns it into the field's value.
  std::string& text = Keep<std::string>();
  CLI::Option* o = AppOf(app_)->add_option(names, text, help)->check(CLI::IsMember(keys));
  o->each([keys, set](const std::string& v) {
    for (size_t i = 0; i < keys.size(); ++i) {
      if (keys[i] == v) set(i);
    }
  });
  return Arg(o);
}
Arg Command::Get(const std::string& name) { return Arg(AppOf(app_)->get_option(name)); }

void Command::Footer(const std::string& text) { AppOf(app_)->footer(text); }
void Command::RequireSubcommand() { AppOf(app_)->require_subcommand(1); }
namespace {

// An options struct's Check() names the field ("RenderOptions::repeat_level = 0; must be ...");
// the user typed an option. When one of the command's options is the field's name in kebab case
// (--repeat-level), the message starts with it: "--repeat-level: RenderOptions::repeat_level ...".
std::string NameTheOption(const CLI::App& app, const std::string& message) {
  const size_t colons = message.find("::");
  const size_t equals = message.find(" = ");
  if (colons == std::string::npos || equals == std::string::npos || equals < colons) return message;
  std::string field = message.substr(colons + 2, equals - colons - 2);
  field = field.substr(field.find_last_of('.') + 1);  // "density.radius" -> "radius"
  field = field.substr(0, field.find('['));           // "alpha[2]" -> "alpha"
  if (field.empty() || field.find_first_of(" ()") != std::string::npos) return message;
  std::string option = "--" + field;
  std::replace(option.begin(), option.end(), '_', '-');
  for (const CLI::Option* o : app.get_options()) {
    for (const std::string& name : o->get_lnames()) {
      if ("--" + name == option) return option + ": " + message;
    }
  }
  return message;
}

}  // namespace

void Command::Run(std::function<int()> run) {
  CLI::App* app = AppOf(app_);
  std::function<int()>* target = run_;
  app->callback([app, target, run] {
    if (!app->get_subcommands().empty()) return;  // a subcommand of this one runs instead
    *target = [app, run] {
      try {
        return run();
      } catch (const std::invalid_argument& e) {
        const std::string named = NameTheOption(*app, e.what());
        if (named == e.what()) throw;
        throw std::invalid_argument(named);
      }
    };
  });
}

int RunCli(int argc, char** argv) {
  // Named, so that the usage lines say `candi`, not the path the executable was called by.
  CLI::App app{"candi: heritage records (photos, CAD sections, old photos) to one point archive, "
               "rendered see-through with stochastic point-based rendering", "candi"};
  app.set_version_flag("--version", std::string("candi ") + kVersion);
  app.require_subcommand(1);
  int verbose = 0;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbose, "More log output (debug)");
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors");
  app.footer("Exit codes: 0 ok, 1 usage, 2 bad input, 3 internal error.\n"
             "Run `candi <command> --help` for a command's options.");
  std::function<int()> run;
  std::vector<std::shared_ptr<void>> kept;
  Command root(&app, &run, &kept);
  // In the order of CommandGroups().
  AddInfo(root);
  AddConvert(root);
  AddCompare(root);
  AddSfm(root);
  AddDense(root);
  AddGeoref(root);
  AddRegister(root);
  AddRegisterScans(root);
  AddClean(root);
  AddColorCorrect(root);
  AddFoundation(root);
  AddReliefCommands(root);
  AddBuild(root);
  AddPack(root);
  AddExport(root);
  AddRender(root);
  AddView(root);
  AddPublish(root);
  AddSection(root);
  AddOpacity(root);
  AddDemo(root);
  AddCampaign(root);
  AddBench(root);
  GroupCommands(app);
  AddGlobalFlags(app, verbose, quiet);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kUsage;
  }
  SetupLogging(quiet ? -1 : verbose);
  SetConsoleProgressEnabled(!quiet);
  return run ? run() : kUsage;
}

}  // namespace candi::apps
