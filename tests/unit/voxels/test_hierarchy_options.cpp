#include <gtest/gtest.h>

#include "common/error.hpp"
#include "voxels/hierarchy_options.hpp"

using namespace qte;

namespace {
cli::Usage usage_with(const std::vector<cli::OptionSpec>& group) {
  cli::Usage u;
  u.name = "tool";
  u.add_options(group);
  return u;
}
}  // namespace

TEST(HierarchyOptions, DefaultsAreThePublishedHierarchy) {
  const cli::Usage u = usage_with(voxels::hierarchy_options());
  const voxels::CoarseToFine h = voxels::parse_hierarchy(cli::parse(u, {}));
  const voxels::CoarseToFine published;
  EXPECT_EQ(h.voxels(), 16);
  EXPECT_EQ(h.depths, 2);
  EXPECT_EQ(h.offsets_m, published.offsets_m);
  EXPECT_EQ(h.scene.min_corner, published.scene.min_corner);
  EXPECT_EQ(h.scene.size_m, published.scene.size_m);
}

TEST(HierarchyOptions, ParsesAndRefusesAsUsageErrors) {
  const cli::Usage u = usage_with(voxels::hierarchy_options());
  const auto h = voxels::parse_hierarchy(
      cli::parse(u, {"--voxels", "8", "--depths", "3", "--offset", "0.15,0.05", "--bounds=-1,-1,0,2"}));
  EXPECT_EQ(h.voxels(), 8);
  EXPECT_EQ(h.offsets_m, (std::vector<double>{0.15, 0.05}));
  EXPECT_EQ(h.scene.min_corner, Eigen::Vector3d(-1, -1, 0));
  EXPECT_THROW(voxels::parse_hierarchy(cli::parse(u, {"--depths", "3"})), UsageError);  // one offset for 3 depths
  EXPECT_THROW(voxels::parse_hierarchy(cli::parse(u, {"--offset", "-0.1"})), UsageError);
  EXPECT_THROW(voxels::parse_hierarchy(cli::parse(u, {"--bounds", "0,0,0"})), UsageError);
  EXPECT_THROW(voxels::parse_hierarchy(cli::parse(u, {"--voxels", "2"}), 4, 128), UsageError);
}

TEST(HierarchyOptions, CheckpointHierarchyRefusesDisagreement) {
  const cli::Usage u = usage_with(voxels::checkpoint_hierarchy_options());
  voxels::CoarseToFine trained;
  trained.offsets_m = {0.2};
  const auto h = voxels::checkpoint_hierarchy(cli::parse(u, {}), trained, 16, 2, "c.rec");
  EXPECT_EQ(h.offsets_m, trained.offsets_m);
  EXPECT_NO_THROW(voxels::checkpoint_hierarchy(cli::parse(u, {"--offset", "0.2", "--voxels", "16"}), trained, 16, 2, "c"));
  for (const std::vector<std::string>& given : std::vector<std::vector<std::string>>{
           {"--offset", "0.15"}, {"--voxels", "8"}, {"--depths", "3"}, {"--bounds=-0.3,-0.5,0.7,1"}})
    EXPECT_THROW(voxels::checkpoint_hierarchy(cli::parse(u, given), trained, 16, 2, "c.rec"), UsageError) << given[0];
  // A checkpoint that kept no hierarchy takes the options as given.
  const auto old = voxels::checkpoint_hierarchy(cli::parse(u, {"--offset", "0.1"}), std::nullopt, 16, 2, "c.rec");
  EXPECT_EQ(old.offsets_m, std::vector<double>{0.1});
}
