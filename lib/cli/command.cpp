#include "cli/command.hpp"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <sstream>

#include "cli/build_commit.hpp"
#include "common/error.hpp"
#include "common/standard_streams.hpp"
#include "common/number_list.hpp"

#ifndef QTE_VERSION
#define QTE_VERSION "unknown"
#endif

namespace qte::cli {
namespace {

// Upper bounds that stand for "no bound" (INT64_MAX, 1e30): --help and the errors leave them unsaid.
constexpr double kUnboundedInteger = 9.2e18;  // INT64_MAX as a double is 2^63
constexpr double kUnboundedReal = 1e30;

// Options every tool has, appended to the tool's own.
std::vector<OptionSpec> common_options(const Usage& usage) {
  return {
      integer_option("seed", "N",
                     usage.uses_randomness
                         ? "seed of every random choice this tool makes; same inputs and seed give the same "
                           "output bytes"
                         : "accepted for uniform pipelines; this tool makes no random choices",
                     "0", 0, INT64_MAX),
      {"help", "", "print this help and exit", ""},
      {"help-man", "", "print this help as a man page (roff) and exit", ""},
      {"version", "", "print the toolkit version and the commit it was built from, and exit", ""},
  };
}

std::vector<OptionSpec> all_options(const Usage& usage) {
  std::vector<OptionSpec> options = usage.options;
  for (auto& o : common_options(usage)) options.push_back(o);
  return options;
}

const OptionSpec* find_option(const std::vector<OptionSpec>& options, const std::string& name) {
  for (const auto& o : options)
    if (o.name == name) return &o;
  return nullptr;
}

std::string synopsis(const Usage& usage) {
  std::string s = usage.name + " [OPTIONS]";
  for (const auto& a : usage.arguments) {
    std::string arg = a.name + (a.variadic ? "..." : "");
    s += " " + (a.optional ? "[" + arg + "]" : arg);
  }
  return s;
}

std::string option_label(const OptionSpec& o) {
  return "--" + o.name + (o.value_name.empty() ? "" : " " + o.value_name);
}

std::string option_help(const OptionSpec& o) {
  std::string h = o.help;
  if (o.required) h += " (required)";
  const std::string range = o.number != OptionSpec::Number::none ? range_text(o) : "";
  if (!range.empty() && !o.default_value.empty()) h += " (" + range + "; default: " + o.default_value + ")";
  else if (!range.empty()) h += " (" + range + ")";
  else if (!o.default_value.empty()) h += " (default: " + o.default_value + ")";
  if (o.repeatable) h += "; may be repeated";
  return h;
}

// Wraps `text` to `width` columns with `indent` spaces before every line.
std::string wrap(const std::string& text, std::size_t indent, std::size_t width = 80) {
  std::istringstream words(text);
  std::string word, line, out;
  const std::string pad(indent, ' ');
  while (words >> word) {
    if (!line.empty() && indent + line.size() + 1 + word.size() > width) {
      out += pad + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out += pad + line + "\n";
  return out;
}

// Escapes text for roff: backslashes, and leading dots or quotes.
std::string roff(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\\') out += "\\e";
    else if (c == '-') out += "\\-";
    else out += c;
  }
  if (!out.empty() && (out[0] == '.' || out[0] == '\'')) out = "\\&" + out;
  return out;
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

const char* kCommonExitStatus =
    "0 on success; 1 on an error, reported as one line on standard error naming the file, "
    "record and byte offset where it applies; 2 on a usage error; 141 when the reader of "
    "standard output went away (as for SIGPIPE).";

}  // namespace

ArgumentSpec input_file(const std::string& what) {
  return {"FILE", what + "; '-' or absent is standard input", true, false};
}

ArgumentSpec input_files(const std::string& what) {
  return {"FILE", what + "; '-' or absent is standard input", true, true};
}

OptionSpec output_file() { return {"output", "FILE", "where to write; '-' is standard output", "-"}; }

bool Arguments::has(const std::string& name) const { return given_.count(name) > 0; }

bool Arguments::flag(const std::string& name) const { return has(name); }

std::vector<std::string> Arguments::list(const std::string& name) const {
  const std::string v = text(name);
  std::vector<std::string> items;
  for (std::size_t at = 0; at <= v.size();) {
    const std::size_t comma = std::min(v.find(',', at), v.size());
    items.push_back(v.substr(at, comma - at));
    if (items.back().empty()) throw UsageError("--" + name + ": expected comma-separated names, got '" + v + "'");
    at = comma + 1;
  }
  return items;
}

std::vector<std::pair<std::string, std::string>> Arguments::assignments(const std::string& name) const {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const std::string& item : all(name)) {
    const std::size_t equals = item.find('=');
    if (equals == std::string::npos || equals == 0)
      throw UsageError("--" + name + ": expected NAME=VALUE, got '" + item + "'");
    pairs.emplace_back(item.substr(0, equals), item.substr(equals + 1));
  }
  return pairs;
}

bool Arguments::declared(const std::string& name) const {
  const auto options = all_options(*usage_);
  return find_option(options, name) != nullptr;
}

std::string Arguments::text(const std::string& name) const {
  auto it = given_.find(name);
  if (it != given_.end()) return it->second.back();
  const auto options = all_options(*usage_);
  const OptionSpec* o = find_option(options, name);
  if (!o) throw Error("internal: option --" + name + " is not declared");
  return o->default_value;
}

int64_t Arguments::parse_integer(const std::string& name) const {
  const std::string v = text(name);
  try {
    std::size_t used = 0;
    const long long n = std::stoll(v, &used, 0);
    if (used == v.size()) return n;
  } catch (const std::exception&) {
  }
  throw UsageError("--" + name + ": expected an integer, got '" + v + "'");
}

// "0..1", "1..4096", "1 or more": a range as --help and the errors write it; a bound past any
// value a run could use (INT64_MAX, 1e30) is left unsaid.
static std::string integer_range_text(int64_t lo, int64_t hi) {
  if (hi >= kUnboundedInteger) return std::to_string(lo) + " or more";
  return std::to_string(lo) + ".." + std::to_string(hi);
}

// An integer option's upper bound as an integer (a double of INT64_MAX does not convert back).
static int64_t integer_high(const OptionSpec& o) {
  return o.high >= kUnboundedInteger ? INT64_MAX : static_cast<int64_t>(o.high);
}

int64_t Arguments::integer(const std::string& name, int64_t lo, int64_t hi) const {
  const int64_t n = parse_integer(name);
  if (n < lo || n > hi)
    throw UsageError("--" + name + " must be " + integer_range_text(lo, hi) + ", got " + text(name));
  return n;
}

double Arguments::parse_real(const std::string& name) const {
  const std::string v = text(name);
  try {
    std::size_t used = 0;
    const double x = std::stod(v, &used);
    if (used == v.size()) return x;
  } catch (const std::exception&) {
  }
  throw UsageError("--" + name + ": expected a number, got '" + v + "'");
}

static std::string real_range_text(double lo, double hi) {
  std::ostringstream range;
  range << lo;
  if (hi >= kUnboundedReal)
    range << " or more";
  else
    range << ".." << hi;
  return range.str();
}

double Arguments::real(const std::string& name, double lo, double hi) const {
  const double x = parse_real(name);
  if (!std::isfinite(x) || x < lo || x > hi)
    throw UsageError("--" + name + " must be " + real_range_text(lo, hi) + ", got " + text(name));
  return x;
}

OptionSpec Arguments::ranged(const std::string& name, OptionSpec::Number number) const {
  const std::vector<OptionSpec> options = all_options(*usage_);
  const OptionSpec* o = find_option(options, name);
  if (!o || o->number != number) throw Error("internal: option --" + name + " is not declared with its range");
  return *o;
}

int64_t Arguments::integer(const std::string& name) const {
  const OptionSpec o = ranged(name, OptionSpec::Number::integer);
  return integer(name, static_cast<int64_t>(o.low), integer_high(o));
}

double Arguments::real(const std::string& name) const {
  const OptionSpec o = ranged(name, OptionSpec::Number::real);
  return real(name, o.low, o.high);
}

OptionSpec integer_option(std::string name, std::string value_name, std::string help, std::string default_value,
                          int64_t low, int64_t high) {
  OptionSpec o{std::move(name), std::move(value_name), std::move(help), std::move(default_value)};
  o.number = OptionSpec::Number::integer;
  o.low = static_cast<double>(low);
  o.high = static_cast<double>(high);
  return o;
}

OptionSpec real_option(std::string name, std::string value_name, std::string help, std::string default_value,
                       double low, double high) {
  OptionSpec o{std::move(name), std::move(value_name), std::move(help), std::move(default_value)};
  o.number = OptionSpec::Number::real;
  o.low = low;
  o.high = high;
  return o;
}

std::string range_text(const OptionSpec& o) {
  if (o.number == OptionSpec::Number::integer)
    return integer_range_text(static_cast<int64_t>(o.low), integer_high(o));
  return real_range_text(o.low, o.high);
}

void check_range(const std::vector<OptionSpec>& options, const std::string& name, double value,
                 const std::string& where) {
  const OptionSpec* o = find_option(options, name);
  if (!o || o->number == OptionSpec::Number::none) throw Error("internal: option --" + name + " has no declared range");
  if (!std::isfinite(value) || value < o->low || value > o->high) {
    std::ostringstream got;
    got.precision(17);
    got << value;
    throw Error(where + ": " + name + " must be " + range_text(*o) + " (--" + name + "), got " + got.str());
  }
}

std::string default_text(int64_t value) { return std::to_string(value); }

std::string default_text(double value) {
  char text[64];
  for (int decimals = 0; decimals <= 17; ++decimals) {
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
    if (std::strtod(text, nullptr) == value) return text;
  }
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::pair<double, double> Arguments::range(const std::string& name) const {
  const std::vector<double> v = parse_reals(name, text(name), 2);
  if (!(v[0] < v[1])) throw UsageError("--" + name + ": expected LO,HI with LO < HI, got '" + text(name) + "'");
  return {v[0], v[1]};
}

std::pair<int, int> Arguments::size(const std::string& name, int min_width, int min_height, int max_width,
                                    int max_height) const {
  const std::string v = text(name);
  const std::size_t x = v.find('x');
  const auto whole_number = [](const std::string& digits) {
    return !digits.empty() && digits.size() <= 9 && digits.find_first_not_of("0123456789") == std::string::npos;
  };
  if (x != std::string::npos && whole_number(v.substr(0, x)) && whole_number(v.substr(x + 1))) {
    const int width = std::stoi(v.substr(0, x)), height = std::stoi(v.substr(x + 1));
    if (width >= min_width && width <= max_width && height >= min_height && height <= max_height) return {width, height};
  }
  throw UsageError("--" + name + ": expected WxH between " + std::to_string(min_width) + "x" + std::to_string(min_height) +
                   " and " + std::to_string(max_width) + "x" + std::to_string(max_height) + ", got '" + v + "'");
}

std::size_t Arguments::choice(const std::string& name, const std::vector<std::string>& choices) const {
  const std::string v = text(name);
  std::string listed;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    if (choices[i] == v) return i;
    listed += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
  }
  throw UsageError("--" + name + ": expected " + listed + ", got '" + v + "'");
}

std::vector<double> Arguments::reals(const std::string& name, std::size_t count) const {
  return parse_reals(name, text(name), count);
}

std::vector<double> parse_reals(const std::string& option, const std::string& text, std::size_t count) {
  std::vector<double> v;
  std::string bad;
  if (!parse_number_list(text, v, bad)) throw UsageError("--" + option + ": '" + bad + "' is not a finite number");
  if (v.size() != count)
    throw UsageError("--" + option + ": expected " + std::to_string(count) + " comma-separated numbers");
  return v;
}

std::vector<std::string> Arguments::all(const std::string& name) const {
  auto it = given_.find(name);
  return it == given_.end() ? std::vector<std::string>{} : it->second;
}

Arguments parse(const Usage& usage, const std::vector<std::string>& argv) {
  Arguments args;
  args.usage_ = &usage;
  const auto options = all_options(usage);
  bool options_done = false;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (options_done || a == "-" || a.size() < 2 || a.compare(0, 2, "--") != 0) {
      if (!options_done && a.size() > 1 && a[0] == '-' && a != "-")
        throw UsageError("unknown option '" + a + "' (options are --long-names)");
      args.positional_.push_back(a);
      continue;
    }
    if (a == "--") {
      options_done = true;
      continue;
    }
    std::string name = a.substr(2), value;
    bool inline_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      inline_value = true;
    }
    const OptionSpec* o = find_option(options, name);
    if (!o) throw UsageError("unknown option --" + name);
    if (o->value_name.empty()) {
      if (inline_value) throw UsageError("--" + name + " takes no value");
    } else if (!inline_value) {
      if (i + 1 >= argv.size()) throw UsageError("--" + name + " needs a value " + o->value_name);
      value = argv[++i];
    }
    auto& values = args.given_[name];
    if (!values.empty() && !o->repeatable && !o->value_name.empty())
      throw UsageError("--" + name + " given twice");
    values.push_back(value);
  }
  if (args.has("help") || args.has("help-man") || args.has("version")) return args;
  for (const auto& o : options)
    if (o.required && !args.has(o.name)) throw UsageError(option_label(o) + " is required");
  std::size_t required = 0, max = 0;
  bool unbounded = false;
  for (const auto& spec : usage.arguments) {
    if (!spec.optional) ++required;
    ++max;
    unbounded |= spec.variadic;
  }
  if (args.positional_.size() < required)
    throw UsageError("missing argument " + usage.arguments[args.positional_.size()].name);
  if (!unbounded && args.positional_.size() > max)
    throw UsageError("unexpected argument '" + args.positional_[max] + "'");
  args.seed();  // validates --seed early
  return args;
}

std::string help_text(const Usage& usage) {
  std::string out = usage.name + " - " + usage.summary + "\n\nUsage: " + synopsis(usage) + "\n";
  for (const auto& p : usage.description) out += "\n" + wrap(p, 2);
  if (!usage.arguments.empty()) {
    out += "\nArguments:\n";
    for (const auto& a : usage.arguments) out += "  " + a.name + "\n" + wrap(a.help, 6);
  }
  out += "\nOptions:\n";
  for (const auto& o : all_options(usage))
    out += "  " + option_label(o) + "\n" + wrap(option_help(o), 6);
  if (!usage.examples.empty()) {
    out += "\nExamples:\n";
    for (const auto& e : usage.examples) out += "  " + e.command + "\n" + wrap(e.explanation, 6);
  }
  if (!usage.environment.empty()) out += "\nEnvironment:\n" + wrap(usage.environment, 2);
  out += "\nExit status:\n" + wrap(kCommonExitStatus, 2);
  if (!usage.exit_status.empty()) out += wrap(usage.exit_status, 2);
  if (!usage.see_also.empty()) {
    out += "\nSee also:\n  ";
    for (std::size_t i = 0; i < usage.see_also.size(); ++i)
      out += (i ? ", " : "") + usage.see_also[i];
    out += "\n";
  }
  return out;
}

std::string man_page(const Usage& usage) {
  std::string out;
  out += ".\\\" Generated by '" + usage.name + " --help-man'; edit the tool's usage(), not this.\n";
  out += ".TH " + upper(usage.name) + " 1 \"\" \"QTE toolkit " QTE_VERSION "\" \"QTE toolkit\"\n";
  out += ".SH NAME\n" + roff(usage.name) + " \\- " + roff(usage.summary) + "\n";
  out += ".SH SYNOPSIS\n.B " + roff(synopsis(usage)) + "\n";
  out += ".SH DESCRIPTION\n";
  for (std::size_t i = 0; i < usage.description.size(); ++i)
    out += (i ? ".PP\n" : "") + roff(usage.description[i]) + "\n";
  if (!usage.arguments.empty()) {
    out += ".SH ARGUMENTS\n";
    for (const auto& a : usage.arguments) out += ".TP\n.I " + roff(a.name) + "\n" + roff(a.help) + "\n";
  }
  out += ".SH OPTIONS\n";
  for (const auto& o : all_options(usage)) {
    out += ".TP\n.B \\-\\-" + roff(o.name) + (o.value_name.empty() ? "" : " \\fI" + roff(o.value_name) + "\\fR") + "\n";
    out += roff(option_help(o)) + "\n";
  }
  if (!usage.examples.empty()) {
    out += ".SH EXAMPLES\n";
    for (const auto& e : usage.examples)
      out += ".PP\n.nf\n" + roff(e.command) + "\n.fi\n.RS\n" + roff(e.explanation) + "\n.RE\n";
  }
  if (!usage.environment.empty()) out += ".SH ENVIRONMENT\n" + roff(usage.environment) + "\n";
  out += ".SH EXIT STATUS\n" + roff(kCommonExitStatus) + "\n";
  if (!usage.exit_status.empty()) out += ".PP\n" + roff(usage.exit_status) + "\n";
  if (!usage.see_also.empty()) {
    out += ".SH SEE ALSO\n";
    for (std::size_t i = 0; i < usage.see_also.size(); ++i) {
      const std::string& s = usage.see_also[i];
      const auto paren = s.find('(');
      out += ".BR " + roff(s.substr(0, paren)) + " " + s.substr(paren) +
             (i + 1 < usage.see_also.size() ? " ," : "") + "\n";
    }
  }
  return out;
}

void check_standard_output() {
  const int error = errno;
  if (std::cout.flush()) return;
  // Only a reader that went away is a closed pipe (exit 141, quietly); a full disk or
  // /dev/full is an error to report.
  struct stat info {};
  if (::fstat(STDOUT_FILENO, &info) == 0 && (S_ISFIFO(info.st_mode) || S_ISSOCK(info.st_mode))) throw BrokenPipe();
  throw Error(std::string("cannot write standard output") +
              (errno != error && errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
}

int run_tool(int argc, char** argv, const Usage& usage,
             const std::function<void(const Arguments&)>& run) {
  // EPIPE arrives as an error from write() instead of killing the process; see BrokenPipe.
  ::signal(SIGPIPE, SIG_IGN);
  // Likewise EFBIG for the file-size limit (SIGXFSZ would kill the process half-way through a
  // record): the writers then cut back what they wrote, as for a full disk.
  ::signal(SIGXFSZ, SIG_IGN);
  reopen_closed_standard_streams();
  const std::string prefix = usage.name + ": ";
  try {
    const Arguments args = parse(usage, std::vector<std::string>(argv + 1, argv + argc));
    if (args.has("help")) {
      std::cout << help_text(usage);
      return 0;
    }
    if (args.has("help-man")) {
      std::cout << man_page(usage);
      return 0;
    }
    if (args.has("version")) {
      std::cout << usage.name << " (QTE toolkit) " << QTE_VERSION << ", commit " << build_commit() << "\n";
      return 0;
    }
    run(args);
    check_standard_output();
    return 0;
  } catch (const BrokenPipe&) {
    return 141;
  } catch (const UsageError& e) {
    std::cerr << prefix << e.what() << " (see " << usage.name << " --help)\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << prefix << "out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << prefix << e.what() << "\n";
    return 1;
  }
}

}  // namespace qte::cli
