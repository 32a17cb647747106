#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "cli/command.hpp"
#include "common/error.hpp"

using namespace qte;

namespace {
cli::Usage usage() {
  cli::Usage u;
  u.name = "demo-tool";
  u.summary = "does a thing";
  u.description = {"Long text."};
  u.arguments = {{"FILE", "input", true, true}};
  u.options = {{"k", "N", "branches", "10"}, {"json", "", "JSON output", ""},
               {"type", "T", "filter", "", true}};
  return u;
}
}  // namespace

TEST(Command, ParsesOptionsDefaultsAndPositionals) {
  const auto u = usage();
  auto a = cli::parse(u, {"--k", "5", "x.rec", "--json", "--type=obs", "--type", "action", "-"});
  EXPECT_EQ(a.integer("k", 1, 100), 5);
  EXPECT_TRUE(a.flag("json"));
  EXPECT_EQ(a.all("type"), (std::vector<std::string>{"obs", "action"}));
  EXPECT_EQ(a.positional(), (std::vector<std::string>{"x.rec", "-"}));
  EXPECT_EQ(a.seed(), 0u);
  auto b = cli::parse(u, {"--seed", "42"});
  EXPECT_EQ(b.integer("k", 1, 100), 10);
  EXPECT_EQ(b.seed(), 42u);
}

TEST(Command, RejectsBadUsage) {
  const auto u = usage();
  EXPECT_THROW(cli::parse(u, {"--nope"}), UsageError);
  EXPECT_THROW(cli::parse(u, {"-k"}), UsageError);
  EXPECT_THROW(cli::parse(u, {"--k"}), UsageError);
  EXPECT_THROW(cli::parse(u, {"--k", "1", "--k", "2"}), UsageError);
  EXPECT_THROW(cli::parse(u, {"--json=yes"}), UsageError);
  EXPECT_THROW(cli::parse(u, {"--seed", "x"}), UsageError);
  EXPECT_THROW(cli::parse(u, {"--k", "ten"}).integer("k", 1, 100), UsageError);
  EXPECT_THROW(cli::parse(u, {"--seed", "-1"}), UsageError);
}

// Numbers are range-checked where they are read: nothing wraps, nothing non-finite passes.
TEST(Command, NumbersSizesAndRangesAreBounded) {
  cli::Usage u = usage();
  u.options.push_back({"size", "WxH", "picture size", "800x500"});
  u.options.push_back({"y-range", "LO,HI", "axis", "0,1"});
  u.options.push_back({"rate", "R", "rate", "0.5"});
  const auto parse = [&](std::vector<std::string> argv) { return cli::parse(u, argv); };
  EXPECT_EQ(parse({"--size", "640x480"}).size("size", 200, 150, 10000, 10000), std::make_pair(640, 480));
  for (const char* bad : {"4294967496x300", "-640x480", "640x", "640x480x2", "640X480", "0x0", "640x100", " 640x480"})
    EXPECT_THROW(parse({"--size", bad}).size("size", 200, 150, 10000, 10000), UsageError) << bad;
  EXPECT_EQ(parse({"--y-range", "-1,2.5"}).range("y-range"), std::make_pair(-1.0, 2.5));
  for (const char* bad : {"1,1", "2,1", "0,inf", "nan,1", "0", "0,1,2", "0,1e999"})
    EXPECT_THROW(parse({"--y-range", bad}).range("y-range"), UsageError) << bad;
  EXPECT_THROW(parse({"--k", "4294967297"}).integer("k", 1, 100), UsageError);
  EXPECT_THROW(parse({"--k", "99999999999999999999"}).integer("k", 1, INT64_MAX), UsageError);
  EXPECT_THROW(parse({"--rate", "-0.1"}).real("rate", 0, 1), UsageError);
  EXPECT_THROW(parse({"--rate", "nan"}).real("rate", 0, 1), UsageError);
  EXPECT_THROW(parse({"--rate", "inf"}).real("rate", 0, INFINITY), UsageError);
}

TEST(Command, HelpAndManPageCoverEveryOption) {
  const auto u = usage();
  const std::string help = cli::help_text(u), man = cli::man_page(u);
  for (const char* o : {"k", "json", "type", "seed", "help", "version"}) {
    EXPECT_NE(help.find(std::string("--") + o), std::string::npos) << o;
    EXPECT_NE(man.find(std::string("\\-\\-") + o), std::string::npos) << o;
  }
  EXPECT_NE(man.find(".TH DEMO-TOOL 1"), std::string::npos);
  EXPECT_NE(help.find("(default: 10)"), std::string::npos);
}

TEST(Command, RequiredOptionsChoicesAndInputs) {
  cli::Usage u = usage();
  u.arguments = {cli::input_files()};
  u.add_options({{"checkpoint", "FILE", "networks", "", false, true}, {"band", "KIND", "std, ci or none", "std"}});
  try {
    cli::parse(u, {"x.rec"});
    ADD_FAILURE() << "a missing required option was accepted";
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "--checkpoint FILE is required");
  }
  EXPECT_NO_THROW(cli::parse(u, {"--help"}));  // help needs no required option
  const auto a = cli::parse(u, {"--checkpoint", "c.rec", "--band", "none"});
  EXPECT_EQ(a.inputs(), std::vector<std::string>{"-"});  // none given: standard input
  EXPECT_EQ(a.input(), "-");
  EXPECT_EQ(a.choice("band", {"std", "ci", "none"}), 2u);
  try {
    cli::parse(u, {"--checkpoint", "c", "--band", "sem"}).choice("band", {"std", "ci", "none"});
    ADD_FAILURE() << "an unknown choice was accepted";
  } catch (const UsageError& e) {
    EXPECT_STREQ(e.what(), "--band: expected std, ci or none, got 'sem'");
  }
  const auto b = cli::parse(u, {"--checkpoint", "c", "a.rec", "b.rec"});
  EXPECT_EQ(b.inputs(), (std::vector<std::string>{"a.rec", "b.rec"}));
  EXPECT_EQ(b.input(), "a.rec");
  const std::string help = cli::help_text(u);
  EXPECT_NE(help.find("networks (required)"), std::string::npos);
  EXPECT_NE(help.find("'-' or absent is standard input"), std::string::npos);
}

// An option declared with its type and range: the one-argument readers check that range, the help
// shows it, and check_range holds a value from elsewhere to it; reading it as another type, or an
// option declared without a range, is a programming error.
TEST(Command, RangesDeclaredWithTheOption) {
  cli::Usage u = usage();
  u.options.push_back(cli::integer_option("batch", "B", "transitions per step", "32", 1, 100000));
  u.options.push_back(cli::real_option("gamma", "G", "discount", "0.99", 0, 1));
  EXPECT_EQ(cli::parse(u, {}).integer("batch"), 32);
  EXPECT_DOUBLE_EQ(cli::parse(u, {"--gamma", "0.5"}).real("gamma"), 0.5);
  EXPECT_EQ(cli::parse(u, {"--batch", "100000"}).integer("batch"), 100000);
  for (const char* bad : {"0", "100001", "-3", "1.5", "x"})
    EXPECT_THROW(cli::parse(u, {"--batch", bad}).integer("batch"), UsageError) << bad;
  for (const char* bad : {"-0.01", "1.01", "nan", "inf"})
    EXPECT_THROW(cli::parse(u, {"--gamma", bad}).real("gamma"), UsageError) << bad;
  try {
    cli::parse(u, {"--gamma", "2"}).real("gamma");
    FAIL() << "--gamma 2 accepted";
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()), "--gamma must be 0..1, got 2");
  }
  const cli::Arguments a = cli::parse(u, {});
  EXPECT_THROW(a.real("batch"), Error);  // declared an integer
  EXPECT_THROW(a.integer("k"), Error);   // declared without a range
  const std::string help = cli::help_text(u);
  EXPECT_NE(help.find("transitions per step (1..100000; default: 32)"), std::string::npos) << help;
  EXPECT_NE(help.find("discount (0..1; default: 0.99)"), std::string::npos) << help;
  EXPECT_EQ(cli::range_text(u.options.back()), "0..1");

  EXPECT_NO_THROW(cli::check_range(u.options, "gamma", 1.0, "a checkpoint"));
  EXPECT_THROW(cli::check_range(u.options, "gamma", std::nan(""), "a checkpoint"), Error);
  try {
    cli::check_range(u.options, "batch", 0, "ckpt.rec's settings");
    FAIL() << "batch 0 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "ckpt.rec's settings: batch must be 1..100000 (--batch), got 0");
  }
  EXPECT_THROW(cli::check_range(u.options, "k", 5, "x"), Error);  // no range declared
}
