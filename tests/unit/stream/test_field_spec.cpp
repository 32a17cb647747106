#include <gtest/gtest.h>

#include "stream/field_spec.hpp"

using namespace qte;
using namespace qte::stream;

TEST(FieldSpec, TextScalarArrayAndShape) {
  Record r("reset");
  add_field_from_spec(r, "task=reach_target");
  add_field_from_spec(r, "seed:i64=7");
  add_field_from_spec(r, "pose:f64=0.5,1,2");
  add_field_from_spec(r, "m:float32[2,2]=1,2,3,4");
  EXPECT_EQ(r.string("task"), "reach_target");
  EXPECT_EQ(r.scalar<int64_t>("seed"), 7);
  EXPECT_EQ(r.array<double>("pose").shape, (Shape{3}));
  EXPECT_EQ(r.array<float>("m").shape, (Shape{2, 2}));
  EXPECT_EQ(r.array<float>("m")[3], 4.0f);
}

TEST(FieldSpec, RejectsOutOfRangeAndWrongCounts) {
  Record r("x");
  EXPECT_THROW(add_field_from_spec(r, "a:u8=256"), Error);
  EXPECT_THROW(add_field_from_spec(r, "a:u16=-1"), Error);
  EXPECT_THROW(add_field_from_spec(r, "a:i32[2]=1,2,3"), Error);
  EXPECT_THROW(add_field_from_spec(r, "a:f32=abc"), Error);
  EXPECT_THROW(add_field_from_spec(r, "a:complex=1"), Error);
  EXPECT_THROW(add_field_from_spec(r, "no_equals_sign"), Error);
  EXPECT_THROW(add_field_from_spec(r, "bad/name=1"), Error);
}

TEST(Record, PrefixesOfFieldsWithASuffix) {
  Record r("obs");
  add_field_from_spec(r, "front.rgb:u8=1");
  add_field_from_spec(r, "front.depth:f32=1");
  add_field_from_spec(r, "wrist.rgb:u8=2");
  add_field_from_spec(r, ".rgb_not:u8=3");
  EXPECT_EQ(r.prefixes(".rgb"), (std::vector<std::string>{"front", "wrist"}));
  EXPECT_TRUE(r.prefixes(".points").empty());
  EXPECT_FALSE(ends_with(".rgb", ".rgb"));  // a bare suffix names no camera
}
