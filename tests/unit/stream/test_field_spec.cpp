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
