#include <gtest/gtest.h>

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
  EXPECT_EQ(a.integer("k"), 5);
  EXPECT_TRUE(a.flag("json"));
  EXPECT_EQ(a.all("type"), (std::vector<std::string>{"obs", "action"}));
  EXPECT_EQ(a.positional(), (std::vector<std::string>{"x.rec", "-"}));
  EXPECT_EQ(a.seed(), 0u);
  auto b = cli::parse(u, {"--seed", "42"});
  EXPECT_EQ(b.integer("k"), 10);
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
  EXPECT_THROW(cli::parse(u, {"--k", "ten"}).integer("k"), UsageError);
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
