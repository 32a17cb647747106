// Every tool declares its usage once (a `Usage` value); --help, --version and the man page
// (--help-man, checked against man/ by a test) are generated from it, so they never drift.
// run_tool() parses the command line, runs the tool and is the one place errors are printed.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace qte::cli {

struct OptionSpec {
  std::string name;         // long name without dashes: "type" for --type
  std::string value_name;   // "T"; empty for a flag
  std::string help;
  std::string default_value;  // shown in help; used when the option is absent
  bool repeatable = false;    // may be given several times (values collected in order)
  bool required = false;      // parse() refuses a command line without it
  // A number's type and range, declared with the option (integer_option, real_option): the
  // one-argument Arguments::integer and real check them, --help and the man page show them, and
  // check_range holds a value from elsewhere (a checkpoint's settings) to the same range.
  enum class Number { none, integer, real } number = Number::none;
  double low = 0, high = 0;
};

// Options whose value is a number in low..high; `default_value` as default_text gives it from
// the setting's struct (empty: none).
OptionSpec integer_option(std::string name, std::string value_name, std::string help, std::string default_value,
                          int64_t low, int64_t high);
OptionSpec real_option(std::string name, std::string value_name, std::string help, std::string default_value,
                       double low, double high);
// "1..100000", "0..1", "1e-12..1e+30": a declared range as --help and the errors write it.
std::string range_text(const OptionSpec& option);
// A value of the ranged option `name` (one of `options`) that did not come from the command line:
// an Error naming the option and `where` unless it lies in the declared range.
void check_range(const std::vector<OptionSpec>& options, const std::string& name, double value,
                 const std::string& where);

struct ArgumentSpec {
  std::string name;  // "FILE"
  std::string help;
  bool optional = false;
  bool variadic = false;  // takes the remaining arguments
};

// An option's default as text, from the setting's own initial value (so the value has one home,
// its struct): integers as they are, reals in the fewest plain decimals that read back the same
// (0.000001, not 1e-06).
std::string default_text(double value);
std::string default_text(int64_t value);
inline std::string default_text(int value) { return default_text(static_cast<int64_t>(value)); }
inline std::string default_text(std::size_t value) { return default_text(static_cast<int64_t>(value)); }

// The record-stream input of a filter: one FILE, '-' or absent meaning standard input
// (read with Arguments::input()).
ArgumentSpec input_file(const std::string& what = "input records");
// Streams read one after another; none means standard input (Arguments::inputs()).
ArgumentSpec input_files(const std::string& what = "record streams to read in order");
// The record-stream output of a tool: --output FILE, standard output by default.
OptionSpec output_file();

struct Example {
  std::string command;
  std::string explanation;
};

struct Usage {
  std::string name;     // program name, e.g. "stream-dump"
  std::string summary;  // one line, lower case, no full stop
  std::vector<std::string> description;  // paragraphs
  std::vector<ArgumentSpec> arguments;
  std::vector<OptionSpec> options;
  std::vector<Example> examples;
  std::vector<std::string> see_also;  // "qte-stream(5)"
  // True when the tool draws random numbers; --seed is accepted by every tool either way.
  bool uses_randomness = false;
  std::string exit_status;  // extra text for EXIT STATUS; the common codes are always listed
  std::string environment;  // the environment variables it reads, for ENVIRONMENT (none: no section)

  // Appends an option group shared by several tools (e.g. voxels::hierarchy_options()).
  void add_options(const std::vector<OptionSpec>& group) { options.insert(options.end(), group.begin(), group.end()); }
};

class Arguments {
 public:
  bool flag(const std::string& name) const;
  bool has(const std::string& name) const;       // given on the command line
  bool declared(const std::string& name) const;  // an option of this tool (for groups shared in part)
  std::string text(const std::string& name) const;
  // Every number from a user is range-checked here: an integer outside lo..hi (no value wraps
  // when a tool narrows it), or a real that is not finite or outside lo..hi, is a UsageError.
  int64_t integer(const std::string& name, int64_t lo, int64_t hi) const;
  double real(const std::string& name, double lo, double hi) const;
  // The same within the range declared with the option (integer_option, real_option).
  int64_t integer(const std::string& name) const;
  double real(const std::string& name) const;
  // "LO,HI": two finite numbers, LO < HI.
  std::pair<double, double> range(const std::string& name) const;
  // "WxH" with W in min_width..max_width and H in min_height..max_height.
  std::pair<int, int> size(const std::string& name, int min_width, int min_height, int max_width, int max_height) const;
  // The index of the option's value in `choices`, or a UsageError listing them.
  std::size_t choice(const std::string& name, const std::vector<std::string>& choices) const;
  // Exactly `count` comma-separated finite numbers ("0.1,0,0.8"), or a UsageError naming the option.
  std::vector<double> reals(const std::string& name, std::size_t count) const;
  std::vector<std::string> all(const std::string& name) const;  // repeatable options
  // Comma-separated names ("front,wrist"): at least one, none empty.
  std::vector<std::string> list(const std::string& name) const;
  // Every NAME=VALUE of a repeatable option, in order (NAME not empty, VALUE may be).
  std::vector<std::pair<std::string, std::string>> assignments(const std::string& name) const;
  const std::vector<std::string>& positional() const { return positional_; }
  std::string input() const { return positional_.empty() ? "-" : positional_[0]; }
  std::vector<std::string> inputs() const {
    return positional_.empty() ? std::vector<std::string>{"-"} : positional_;
  }
  uint64_t seed() const { return static_cast<uint64_t>(integer("seed")); }

 private:
  int64_t parse_integer(const std::string& name) const;
  double parse_real(const std::string& name) const;
  OptionSpec ranged(const std::string& name, OptionSpec::Number number) const;
  friend Arguments parse(const Usage& usage, const std::vector<std::string>& argv);
  const Usage* usage_ = nullptr;
  std::map<std::string, std::vector<std::string>> given_;
  std::vector<std::string> positional_;
};

// The list parser behind Arguments::reals, for values of repeatable options.
std::vector<double> parse_reals(const std::string& option, const std::string& text, std::size_t count);

// Throws UsageError on unknown options, missing values, missing required options or wrong
// argument counts.
Arguments parse(const Usage& usage, const std::vector<std::string>& argv);

std::string help_text(const Usage& usage);
std::string man_page(const Usage& usage);  // roff, section 1

// Flushes standard output; a failed write throws BrokenPipe when the reader of a pipe went
// away (exit 141) and Error otherwise (a full disk: one line, exit 1).
void check_standard_output();

// main() of every tool: `return run_tool(argc, argv, usage(), run);`
// Exit status: 0 success, 1 error (one line on stderr), 2 usage error, 141 broken pipe.
int run_tool(int argc, char** argv, const Usage& usage,
             const std::function<void(const Arguments&)>& run);

}  // namespace qte::cli
