#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <string>

#include "stream/field_names.hpp"
#include "stream/record_types.hpp"

using namespace qte;

namespace {

#define QTE_LISTED(constant, name) name,
const std::set<std::string> kNames = {QTE_FIELD_NAMES(QTE_LISTED)};
const std::set<std::string> kCameraSuffixes = {QTE_CAMERA_FIELD_SUFFIXES(QTE_LISTED)};
const std::set<std::string> kDepthSuffixes = {QTE_DEPTH_FIELD_SUFFIXES(QTE_LISTED)};
const std::set<std::string> kRecordTypes = {QTE_RECORD_TYPES(QTE_LISTED)};
#undef QTE_LISTED

// Every field name of the registry, each sorted into what it is: a plain name, a per-camera
// pattern's suffix ("<camera>.rgb"), a per-depth one ("depth<d>.index", or a depth written out,
// "depth0.grid"), or a name of the network's own ("<name>", "depth<d>.<parameter>", Adam's).
struct RegistryNames {
  std::set<std::string> plain, camera_suffixes, depth_suffixes, own;
};

RegistryNames registry_names() {
  RegistryNames r;
  const std::regex per_depth(R"(depth(<d>|[0-9]+)(\.[a-z_]+))");
  for (const stream::RecordType& type : stream::record_types())
    for (const stream::FieldSchema& field : type.fields) {
      const std::string name = field.name;
      std::smatch m;
      if (name.rfind("<camera>", 0) == 0)
        r.camera_suffixes.insert(name.substr(8));
      else if (std::regex_match(name, m, per_depth))
        r.depth_suffixes.insert(m[2]);
      else if (name.find('<') != std::string::npos)
        r.own.insert(name);
      else
        r.plain.insert(name);
    }
  return r;
}

}  // namespace

// The constants every program names fields by are the registry's names, no more and no fewer:
// a field added to the registry (and formats/record-stream.md) gets its constant here, and a
// constant can only name a field the specification has.
TEST(FieldNames, AreTheRegistrysPlainNames) { EXPECT_EQ(kNames, registry_names().plain); }

TEST(FieldNames, CameraSuffixesAreTheRegistrysPerCameraFields) {
  EXPECT_EQ(kCameraSuffixes, registry_names().camera_suffixes);
}

TEST(FieldNames, DepthSuffixesAreTheRegistrysPerDepthFields) {
  EXPECT_EQ(kDepthSuffixes, registry_names().depth_suffixes);
}

TEST(FieldNames, RecordTypesAreTheRegistrys) {
  std::set<std::string> registry;
  for (const stream::RecordType& type : stream::record_types()) registry.insert(type.name);
  EXPECT_EQ(kRecordTypes, registry);
  EXPECT_EQ(stream::find_record_type(record_type::transition)->name, std::string("transition"));
}

// The composed names are the specification's patterns filled in.
TEST(FieldNames, ComposedNames) {
  EXPECT_EQ(fields::depth_field(0, fields::per_depth::index), "depth0.index");
  EXPECT_TRUE(fields::is_per_depth("depth0.index"));
  EXPECT_TRUE(fields::is_per_depth("depth12.conv.weight"));
  EXPECT_FALSE(fields::is_per_depth("depths"));
  EXPECT_FALSE(fields::is_per_depth("depth.index"));
  EXPECT_FALSE(fields::is_per_depth("depth3"));
  EXPECT_FALSE(fields::is_per_depth("adam.depth0.w.step"));
  EXPECT_EQ(fields::depth_field(12, fields::per_depth::argmax_index), "depth12.argmax_index");
  EXPECT_EQ(std::string("front") + fields::per_camera::depth_mm, "front.depth_mm");
  EXPECT_EQ(fields::adam_prefix + fields::depth_prefix(1) + "conv.weight" + fields::per_parameter::exp_avg_sq,
            "adam.depth1.conv.weight.exp_avg_sq");
  const RegistryNames r = registry_names();
  for (const char* suffix : {fields::per_parameter::exp_avg, fields::per_parameter::exp_avg_sq,
                             fields::per_parameter::max_exp_avg_sq, fields::per_parameter::step})
    EXPECT_TRUE(r.own.count(std::string("adam.depth<d>.<parameter>") + suffix)) << suffix;
}
