// The factory reads every model type and rejects bad input with one line that names the problem.
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/io/field_factory.h>

#include <filesystem>
#include <fstream>

#include "common/test_fields.h"

namespace cdp {
namespace {

std::string error_of(const std::string& json) {
  try {
    test::field_from_json(json);
  } catch (const InvalidInputError& e) {
    return e.what();
  }
  return "";
}

TEST(FieldFactory, BuildsEveryBuiltInType) {
  EXPECT_EQ(test::field_from_json(R"({"type": "sphere", "radius": 1})")->type_name(), "sphere");
  EXPECT_EQ(test::field_from_json(R"({"type": "ellipsoid", "radii": [1, 2, 3]})")->type_name(), "ellipsoid");
  EXPECT_EQ(test::field_from_json(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.2})")->type_name(),
            "torus");
  EXPECT_EQ(test::field_from_json(
                R"({"type": "blobs", "threshold": 0.5, "blobs": [{"center": [0,0,0], "radius": 1}]})")
                ->type_name(),
            "blobs");
  EXPECT_EQ(test::field_from_json(R"({"type": "expression", "value": "x", "bounds": [[0,0,0],[1,1,1]]})")
                ->type_name(),
            "expression");
  EXPECT_EQ(test::field_from_json(R"({"type": "double_torus"})")->type_name(), "double_torus");
  const auto types = registered_field_types();
  EXPECT_NE(std::find(types.begin(), types.end(), "tanglecube"), types.end());
}

TEST(FieldFactory, BoundsOverrideTheModelsBox) {
  const auto f = test::field_from_json(R"({"type": "sphere", "radius": 1, "bounds": [[-2,-3,-4],[2,3,4]]})");
  EXPECT_EQ(f->bounds().min, Vec3(-2, -3, -4));
  EXPECT_EQ(f->bounds().max, Vec3(2, 3, 4));
}

TEST(FieldFactory, BoxesOfAnalyticModelsContainTheirSurfaces) {
  const auto s = test::field_from_json(R"({"type": "sphere", "center": [1, 2, 3], "radius": 2})");
  EXPECT_TRUE(s->bounds().contains(Vec3(3, 2, 3)));
  EXPECT_TRUE(s->bounds().contains(Vec3(1, 2, 1)));
  const auto t = test::field_from_json(R"({"type": "torus", "major_radius": 1, "minor_radius": 0.2})");
  EXPECT_TRUE(t->bounds().contains(Vec3(0, -1.2, 0)));
  EXPECT_TRUE(t->bounds().contains(Vec3(1, 0, 0.2)));
}

TEST(FieldFactory, UnknownAndMisspelledKeysAreNamed) {
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": 1, "centre": [0,0,0]})"),
            "<test>: centre: unknown key (did you mean \"center\"?)");
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": 1, "colour": "red"})"), "<test>: colour: unknown key");
  EXPECT_EQ(error_of(R"({"type": "torus", "major_radius": 1, "minor_radus": 0.2})"),
            "<test>: minor_radus: unknown key (did you mean \"minor_radius\"?)");
  EXPECT_EQ(error_of(R"({"type": "torus", "major_radius": 1})"), "<test>: minor_radius: missing required key");
  EXPECT_EQ(error_of(R"({"type": "blobs", "threshold": 0.5, "blobs": [{"center": [0,0,0], "radius": 1, "strenght": 2}]})"),
            "<test>: blobs[0].strenght: unknown key (did you mean \"strength\"?)");
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": 1, "bound": [[0,0,0],[1,1,1]]})"),
            "<test>: bound: unknown key (did you mean \"bounds\"?)");
}

TEST(FieldFactory, WrongTypesAndValuesAreNamed) {
  const std::string unknown = error_of(R"({"type": "spher", "radius": 1})");
  EXPECT_EQ(unknown.rfind("<test>: type: unknown model type \"spher\" (known: blobs, capped_cylinder, double_torus, ", 0), 0u)
      << unknown;
  EXPECT_NE(unknown.find(", sphere, "), std::string::npos) << unknown;
  EXPECT_EQ(error_of(R"({"radius": 1})"), "<test>: type: missing required key");
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": "one"})"), "<test>: radius: expected a number, found a string");
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": -1})"), "<test>: radius: must be positive, found -1.000000");
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": 1, "center": [0, 0]})"),
            "<test>: center: expected 3 numbers [x, y, z], found 2");
  EXPECT_EQ(error_of(R"({"type": "torus", "major_radius": 1, "minor_radius": 2})"),
            "<test>: minor_radius: must be smaller than major_radius (a ring torus)");
  EXPECT_EQ(error_of(R"({"type": "blobs", "kernel": "gauss", "threshold": 1, "blobs": []})"),
            "<test>: kernel: \"gauss\" is not one of \"wyvill\", \"blinn\"");
  EXPECT_EQ(error_of(R"({"type": "blobs", "threshold": 1, "blobs": []})"), "<test>: blobs: needs at least one blob");
  EXPECT_EQ(error_of(R"({"type": "expression", "value": "x"})"),
            "<test>: bounds: missing required key (an expression has no box of its own)");
  EXPECT_EQ(error_of(R"({"type": "expression", "value": "x +", "bounds": [[0,0,0],[1,1,1]]})"),
            "<test>: value: expression: unexpected end of formula at position 4");
  EXPECT_EQ(error_of(R"({"type": "sphere", "radius": 1, "bounds": [[1,0,0],[0,1,1]]})"),
            "<test>: bounds: empty box: every max must exceed its min");
  EXPECT_EQ(error_of(R"([1, 2])"), "<test>: expected a JSON object, found an array");
}

class FieldFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("cdp_factory_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  std::filesystem::path dir_;
};

TEST_F(FieldFiles, LoadsAFieldFile) {
  const auto path = write("torus.json", R"({"type": "torus", "major_radius": 1, "minor_radius": 0.25})");
  EXPECT_EQ(load_field(path)->type_name(), "torus");
}

TEST_F(FieldFiles, MissingAndMalformedFilesAreNamed) {
  try {
    load_field(dir_ / "nope.json");
    FAIL();
  } catch (const InvalidInputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir_ / "nope.json").string() + ": cannot open file");
  }
  const auto bad = write("bad.json", R"({"type": "sphere", "radius": 1,})");
  try {
    load_field(bad);
    FAIL();
  } catch (const InvalidInputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(bad.string() + ": malformed JSON: ", 0), 0u) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line";
  }
  const auto misspelled = write("typo.json", R"({"type": "sphere", "raduis": 1})");
  EXPECT_THROW(load_field(misspelled), InvalidInputError);
}

TEST_F(FieldFiles, DuplicateKeysOverflowingNumbersAndFoldersAreNamedErrors) {
  const auto message = [](const std::filesystem::path& path) {
    try {
      load_field(path);
    } catch (const InvalidInputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  // A key given twice, at the top or nested: nlohmann keeps the last value silently.
  EXPECT_EQ(message(write("twice.json", R"({"type": "sphere", "radius": 1, "radius": 2})")),
            (dir_ / "twice.json").string() + ": the key \"radius\" appears twice in one object");
  EXPECT_NE(message(write("nested.json", R"({"type": "sphere", "radius": 1, "center": [0, 0, 0],
                                             "bounds": {"a": 1, "a": 2}})")).find("\"a\" appears twice"),
            std::string::npos);
  // The same key in two different objects is fine.
  EXPECT_EQ(message(write("two_objects.json", R"({"type": "blobs", "blobs": [{"center": [0, 0, 0], "radius": 1},
                                                   {"center": [0.5, 0, 0], "radius": 1}]})")).find("twice"),
            std::string::npos);
  const std::string overflow = message(write("overflow.json", R"({"type": "sphere", "radius": 1e999})"));
  EXPECT_EQ(overflow.rfind((dir_ / "overflow.json").string() + ": malformed JSON: number overflow", 0), 0u) << overflow;
  std::filesystem::create_directories(dir_ / "folder.json");
  EXPECT_EQ(message(dir_ / "folder.json"), (dir_ / "folder.json").string() + ": is a folder, not a JSON file");
}

// nlohmann's parser keeps its own stack and its values are destroyed without recursion, so a
// field file nested 100000 deep is an error like any other (kept so that it stays that way).
TEST_F(FieldFiles, DeeplyNestedJsonIsAnErrorNotACrash) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  for (const auto& [text, message] :
       {std::pair{deep, "expected a JSON object, found an array"},
        std::pair{R"({"type": "sphere", "radius": )" + deep + "}", "radius: expected a number, found an array"}}) {
    const auto path = write("deep.json", text);
    try {
      load_field(path);
      ADD_FAILURE() << message;
    } catch (const InvalidInputError& e) {
      EXPECT_EQ(std::string(e.what()), path.string() + ": " + message);
    }
  }
}

}  // namespace
}  // namespace cdp
