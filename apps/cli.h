// How a command declares its command line, without CLI11: each command binds its options
// to the fields they set (the library's Options structs, or a few of the command's own), once.
// cli.cc is the one translation unit that includes CLI11 (its headers cost ~10 s each to parse)
// and turns these declarations into CLI11's; the help text is CLI11's, from these declarations.
//
// A command's file (apps/render.cc, ...; commands.h lists them) provides `void AddXxx(Command&
// root)` for each of its commands, which adds the command, keeps its arguments alive with
// Keep<T>(), and names the function that runs it with Run(); cli.cc adds them in the order
// `candi --help` lists them. Option groups several commands share are in option_groups.h.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace candi::apps {

enum ExitCode : int { kOk = 0, kUsage = 1, kBadInput = 2, kInternal = 3 };

// One option or positional argument, as declared.
class Arg {
 public:
  Arg& Required();
  Arg& Range(int lo, int hi);                  // shown as INT:INT in [lo - hi]
  Arg& Range(double lo, double hi);            // shown as FLOAT:FLOAT in [lo - hi]
  Arg& OneOf(const std::vector<std::string>& values);  // shown as TEXT:{a,b,c}
  Arg& Positive();                             // > 0
  Arg& NonNegative();                          // >= 0
  Arg& Excludes(const Arg& other);
  Arg& Needs(const Arg& other);
  Arg& Delimiter(char separator);              // a,b,c gives three values
  Arg& Repeatable();                           // the option may be given several times, one value each
  Arg& OnGiven(std::function<void()> given);   // called when the option is given

 private:
  friend class Command;
  explicit Arg(void* option) : option_(option) {}
  void* option_;  // CLI::Option*
};

class Command {
 public:
  // A subcommand of this command.
  Command Add(const std::string& name, const std::string& description);
  // A subcommand added earlier (`bench`'s subcommands are declared by several groups).
  Command Find(const std::string& name);

  // Options ("-o,--output") and positionals ("input") bound to `value`.
  Arg Option(const std::string& names, std::string& value, const std::string& help);
  Arg Option(const std::string& names, int& value, const std::string& help);
  Arg Option(const std::string& names, double& value, const std::string& help);
  Arg Option(const std::string& names, unsigned long& value, const std::string& help);       // NOLINT
  Arg Option(const std::string& names, unsigned long long& value, const std::string& help);  // NOLINT
  Arg Option(const std::string& names, std::vector<std::string>& values, const std::string& help);
  Arg Option(const std::string& names, std::vector<double>& values, const std::string& help);
  Arg Flag(const std::string& names, bool& value, const std::string& help);
  // A flag that sets `value` to false ("--no-check" for `check`).
  Arg FlagOff(const std::string& names, bool& value, const std::string& help);
  // A choice among names, setting an enum (shown as TEXT:{a,b,c}).
  template <typename Enum>
  Arg Choice(const std::string& names, Enum& value, const std::vector<std::pair<std::string, Enum>>& choices,
             const std::string& help) {
    std::vector<std::string> keys;
    for (const auto& c : choices) keys.push_back(c.first);
    return ChoiceIndex(names, keys, [&value, choices](size_t i) { value = choices[i].second; }, help);
  }
  // An option declared earlier, by one of its names ("--growth").
  Arg Get(const std::string& name);

  void Footer(const std::string& text);
  void RequireSubcommand();
  // The function that runs this command when it is the one given (not one of its subcommands).
  void Run(std::function<int()> run);

  // An object that lives as long as the command line: a command's arguments.
  template <typename T>
  T& Keep() {
    auto object = std::make_shared<T>();
    kept_->push_back(object);
    return *object;
  }

 private:
  friend int RunCli(int argc, char** argv);
  Command(void* app, std::function<int()>* run, std::vector<std::shared_ptr<void>>* kept)
      : app_(app), run_(run), kept_(kept) {}
  Arg ChoiceIndex(const std::string& names, const std::vector<std::string>& keys,
                  std::function<void(size_t)> set, const std::string& help);
  void* app_;  // CLI::App*
  std::function<int()>* run_;
  std::vector<std::shared_ptr<void>>* kept_;
};

// Parses argv, sets up logging and progress, and runs the command given; returns its exit code
// (a usage error's is kUsage). Exceptions of the command propagate (main.cc reports them).
int RunCli(int argc, char** argv);

}  // namespace candi::apps
