// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/config_test.cpp -- JSON config: documented defaults and every error
#include <gtest/gtest.h>

#include "config.h"
#include "penumbra/core/error.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

const char* kMinimal = R"({"output": {"directory": "out"}, "cameras": {"phi": [0], "theta": [0]},
                           "fields": [{"name": "T"}]})";

TEST(Config, MinimalConfigGetsDocumentedDefaults) {
  const Config c = parse_config(kMinimal);
  EXPECT_EQ(c.output_directory, "out");
  EXPECT_EQ(c.if_exists, IfExists::error);
  EXPECT_EQ(c.width, 256);
  EXPECT_EQ(c.height, 256);
  for (float b : c.background) EXPECT_EQ(b, 1.0f);
  ASSERT_TRUE(c.orbit.has_value());
  EXPECT_EQ(c.orbit->fov_y_deg, 30.0);
  EXPECT_TRUE(c.look_at.empty());
  ASSERT_EQ(c.fields.size(), 1u);
  const FieldConfig& f = c.fields[0];
  EXPECT_EQ(f.mode, ComponentMode::magnitude);
  EXPECT_FALSE(f.range.has_value());  // "auto"
  EXPECT_EQ(f.x_units, XUnits::normalized);
  EXPECT_EQ(f.opacity_unit, OpacityUnit::diagonal);
  ASSERT_EQ(f.transfer_function.colors.size(), 3u);
  ASSERT_EQ(f.transfer_function.opacities.size(), 2u);
  EXPECT_EQ(f.transfer_function.opacities[0].a, 0.0);
  EXPECT_EQ(f.transfer_function.opacities[1].a, 4.0);
  EXPECT_EQ(c.trigger.every_cycles, 1);
  EXPECT_EQ(c.trigger.every_time, 0.0);
  EXPECT_EQ(c.backend, Backend::cpu);
}

TEST(Config, FullConfigIsRead) {
  const Config c = parse_config(R"({
    "output": {"directory": "db", "if_exists": "resume"},
    "image": {"width": 64, "height": 32, "background": [0, 0.5, 1]},
    "cameras": {"phi": [0, 45.5], "theta": [-30, 90], "fov": 40,
                "look_at": [{"name": "top", "eye": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 20},
                            {"eye": [5, 0, 0], "target": [0, 0, 0]}]},
    "fields": [{"name": "v", "component": 2, "range": [-1, 3],
                "transfer_function": {"x": "normalized", "opacity_unit": "world",
                                      "colors": [[0, 0, 0, 1], [1, 1, 0, 0]], "opacities": [[0, 0], [0.5, 2], [1, 0]]}},
               {"name": "v", "component": "magnitude", "transfer_function": {"x": "data", "colors": [[-5, 1, 1, 1]]}}],
    "trigger": {"every_cycles": 5, "every_time": 0.25},
    "backend": "auto"})");
  EXPECT_EQ(c.if_exists, IfExists::resume);
  EXPECT_EQ(c.width, 64);
  EXPECT_EQ(c.height, 32);
  EXPECT_EQ(c.background[1], 0.5f);
  EXPECT_EQ(c.orbit->phi, (std::vector<double>{0, 45.5}));
  EXPECT_EQ(c.orbit->theta, (std::vector<double>{-30, 90}));
  EXPECT_EQ(c.orbit->fov_y_deg, 40);
  ASSERT_EQ(c.look_at.size(), 2u);
  EXPECT_EQ(c.look_at[0].name, "top");
  EXPECT_EQ(c.look_at[0].fov_y_deg, 20);
  EXPECT_EQ(c.look_at[1].name, "camera1");  // default name: position in the list
  EXPECT_EQ(c.look_at[1].up.z, 1.0);        // default up: +z
  EXPECT_EQ(c.look_at[1].fov_y_deg, 30.0);
  EXPECT_EQ(c.fields[0].mode, ComponentMode::component);
  EXPECT_EQ(c.fields[0].component, 2);
  EXPECT_EQ(c.fields[0].range->first, -1);
  EXPECT_EQ(c.fields[0].opacity_unit, OpacityUnit::world);
  EXPECT_EQ(c.fields[0].transfer_function.opacities.size(), 3u);
  EXPECT_EQ(c.fields[1].x_units, XUnits::data);
  EXPECT_EQ(c.fields[1].transfer_function.colors.size(), 1u);
  EXPECT_EQ(c.fields[1].transfer_function.opacities.size(), 2u);  // default opacity kept
  EXPECT_EQ(c.trigger.every_cycles, 5);
  EXPECT_EQ(c.trigger.every_time, 0.25);
  EXPECT_EQ(c.backend, Backend::automatic);
  EXPECT_TRUE(c.uses_field("v"));
  EXPECT_FALSE(c.uses_field("T"));
}

TEST(Config, TimeTriggerAloneDisablesTheCycleDefault) {
  const Config c = parse_config(R"({"output": {"directory": "o"}, "cameras": {"look_at": [{"eye": [1,2,3], "target": [0,0,0]}]},
                                    "fields": [{"name": "T"}], "trigger": {"every_time": 2}})");
  EXPECT_EQ(c.trigger.every_cycles, 0);
  EXPECT_EQ(c.trigger.every_time, 2);
  EXPECT_FALSE(c.orbit.has_value());
}

TEST(Config, ReadsAFilePath) {
  testing::TempDir dir;
  const std::string path = dir / "c.json";
  std::ofstream(path) << kMinimal;
  EXPECT_EQ(parse_config(path).output_directory, "out");
  EXPECT_EQ(parse_config("  \n" + std::string(kMinimal)).output_directory, "out");  // text after blanks
}

void expect_error(const std::string& text, ErrorCode code, const std::string& message) {
  try {
    parse_config(text);
    ADD_FAILURE() << "no error for: " << text;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << "got: " << e.what() << "\nwanted: " << message;
  }
}

/// `{...}` with one part replaced: base pieces are output, cameras, fields, extra.
std::string doc(const std::string& output, const std::string& cameras, const std::string& fields,
                const std::string& extra = "") {
  return "{" + output + "," + cameras + "," + fields + extra + "}";
}
const std::string kOut = R"("output": {"directory": "o"})";
const std::string kCams = R"("cameras": {"phi": [0], "theta": [0]})";
const std::string kFields = R"("fields": [{"name": "T"}])";
std::string with_field(const std::string& field) { return doc(kOut, kCams, "\"fields\": [" + field + "]"); }
std::string with_tf(const std::string& tf) { return with_field(R"({"name": "T", "transfer_function": )" + tf + "}"); }

TEST(Config, EveryErrorNamesItsKeyPath) {
  const auto inv = ErrorCode::invalid_argument;
  expect_error("", inv, "config: empty");
  expect_error("/nonexistent/penumbra.json", ErrorCode::io_error, "cannot read file '/nonexistent/penumbra.json'");
  expect_error("{\"output\": ", inv, "is not valid JSON");
  expect_error(doc(kOut, kCams, kFields, R"(, "colour": 1)"), inv, "config: colour is not a known key");
  expect_error(doc(R"("cameras": {"phi": [0], "theta": [0]})", kFields, R"("image": {})"), inv, "config: output is required");
  expect_error(doc(R"("output": {})", kCams, kFields), inv, "config: output.directory is required");
  expect_error(doc(R"("output": {"directory": 3})", kCams, kFields), inv, "config: output.directory must be a string");
  expect_error(doc(R"("output": {"directory": ""})", kCams, kFields), inv, "output.directory must not be empty");
  expect_error(doc(R"("output": {"directory": "o", "if_exists": "overwrite"})", kCams, kFields), inv,
               "config: output.if_exists must be one of \"error\", \"resume\", got \"overwrite\"");
  expect_error(doc(R"("output": "o")", kCams, kFields), inv, "config: output must be an object");
  expect_error(doc(kOut, kCams, kFields, R"(, "image": {"width": 0})"), inv, "config: image.width must be in [1, 16384], got 0");
  expect_error(doc(kOut, kCams, kFields, R"(, "image": {"height": 2.5})"), inv, "config: image.height must be an integer");
  expect_error(doc(kOut, kCams, kFields, R"(, "image": {"background": [1, 1]})"), inv,
               "config: image.background must be [r,g,b]");
  expect_error(doc(kOut, kCams, kFields, R"(, "image": {"background": [1, 1, 2]})"), inv,
               "config: image.background must be [r,g,b] with components in [0,1]");
  expect_error(doc(kOut, kCams, kFields, R"(, "image": {"depth": 8})"), inv, "config: image.depth is not a known key");
  expect_error(doc(kOut, R"("image": {})", kFields), inv, "config: cameras is required");
  expect_error(doc(kOut, R"("cameras": {})", kFields), inv, "config: cameras must define orbit cameras");
  expect_error(doc(kOut, R"("cameras": {"phi": [0]})", kFields), inv, "config: cameras needs both \"phi\" and \"theta\"");
  expect_error(doc(kOut, R"("cameras": {"phi": [], "theta": [0]})", kFields), inv,
               "config: cameras.phi must be a non-empty array of numbers");
  expect_error(doc(kOut, R"("cameras": {"phi": [0, "a"], "theta": [0]})", kFields), inv, "config: cameras.phi[1] must be a number");
  expect_error(doc(kOut, R"("cameras": {"phi": [0], "theta": [95]})", kFields), inv,
               "config: cameras.theta[0] must be in [-90, 90] degrees");
  expect_error(doc(kOut, R"("cameras": {"phi": [0], "theta": [0], "fov": 180})", kFields), inv,
               "config: cameras.fov must be in (0, 180) degrees");
  expect_error(doc(kOut, R"("cameras": {"fov": 10, "look_at": [{"eye": [1,0,0], "target": [0,0,0]}]})", kFields), inv,
               "config: cameras.fov applies to orbit cameras only");
  expect_error(doc(kOut, R"("cameras": {"look_at": {}})", kFields), inv, "config: cameras.look_at must be a non-empty array");
  expect_error(doc(kOut, R"("cameras": {"look_at": [{"target": [0,0,0]}]})", kFields), inv,
               "config: cameras.look_at[0].eye is required");
  expect_error(doc(kOut, R"("cameras": {"look_at": [{"eye": [1,0], "target": [0,0,0]}]})", kFields), inv,
               "config: cameras.look_at[0].eye must be [x,y,z]");
  expect_error(doc(kOut, R"("cameras": {"look_at": [{"eye": [1,0,0], "target": [1,0,0]}]})", kFields), inv,
               "config: cameras.look_at[0] has eye == target");
  expect_error(doc(kOut, R"("cameras": {"look_at": [{"eye": [0,0,1], "target": [0,0,0]}]})", kFields), inv,
               "config: cameras.look_at[0].up must not be parallel");
  expect_error(doc(kOut, R"("cameras": {"look_at": [{"name": "a", "eye": [1,0,0], "target": [0,0,0]},
                                                     {"name": "a", "eye": [2,0,0], "target": [0,0,0]}]})", kFields),
               inv, "config: cameras.look_at[1].name \"a\" is used twice");
  expect_error(doc(kOut, R"("cameras": {"look_at": [{"eye": [1,0,0], "target": [0,0,0], "roll": 3}]})", kFields), inv,
               "config: cameras.look_at[0].roll is not a known key");
  expect_error(doc(kOut, kCams, R"("image": {})"), inv, "config: fields is required");
  expect_error(doc(kOut, kCams, R"("fields": [])"), inv, "config: fields must be a non-empty array");
  expect_error(with_field(R"({"component": 0})"), inv, "config: fields[0].name is required");
  expect_error(with_field(R"({"name": ""})"), inv, "config: fields[0].name must not be empty");
  expect_error(with_field(R"({"name": "T", "association": "point"})"), inv, "config: fields[0].association is not a known key");
  expect_error(with_field(R"({"name": "T", "component": "x"})"), inv,
               "config: fields[0].component must be one of \"magnitude\", got \"x\"");
  expect_error(with_field(R"({"name": "T", "component": -1})"), inv, "config: fields[0].component must be in [0, 63]");
  expect_error(with_field(R"({"name": "T", "component": 1.5})"), inv,
               "config: fields[0].component must be \"magnitude\" or a component index");
  expect_error(with_field(R"({"name": "T", "range": "max"})"), inv, "config: fields[0].range must be one of \"auto\"");
  expect_error(with_field(R"({"name": "T", "range": [2, 1]})"), inv, "config: fields[0].range must have lo < hi");
  expect_error(with_field(R"({"name": "T", "range": [1, 1]})"), inv, "config: fields[0].range must have lo < hi");
  expect_error(with_field(R"({"name": "T", "range": [0, 1, 2]})"), inv, "config: fields[0].range must be \"auto\" or [lo,hi]");
  expect_error(with_field(R"({"name": "T", "range": [0, 1], "transfer_function": {"x": "data"}})"), inv,
               "config: fields[0].range does not apply when transfer_function.x is \"data\"");
  expect_error(with_field(R"({"name": "T"}, {"name": "T", "component": "magnitude"})"), inv,
               "config: fields[1] renders field 'T' with the same component as an earlier entry");
  expect_error(with_tf(R"({"colors": [[0, 0, 0, 0], [1, 1, 1, 1], [0.5, 1, 1]]})"), inv,
               "config: fields[0].transfer_function.colors[2] must be [x,r,g,b]");
  expect_error(with_tf(R"({"colors": [[0, 0, 0, 2]]})"), inv,
               "config: fields[0].transfer_function.colors[0] must be [x,r,g,b] with r, g, b in [0,1]");
  expect_error(with_tf(R"({"colors": [[1, 0, 0, 0], [0, 0, 0, 0]]})"), inv,
               "config: fields[0].transfer_function.colors[1] x must not decrease");
  expect_error(with_tf(R"({"colors": []})"), inv, "config: fields[0].transfer_function.colors must be a non-empty array");
  expect_error(with_tf(R"({"opacities": [[0, -1]]})"), inv,
               "config: fields[0].transfer_function.opacities[0] must be [x,a] with a >= 0");
  expect_error(with_tf(R"({"opacities": [[0, 1, 2]]})"), inv, "config: fields[0].transfer_function.opacities[0] must be [x,a]");
  expect_error(with_tf(R"({"opacities": [[1, 1], [0, 1]]})"), inv,
               "config: fields[0].transfer_function.opacities[1] x must not decrease");
  expect_error(with_tf(R"({"x": "percent"})"), inv, "config: fields[0].transfer_function.x must be one of");
  expect_error(with_tf(R"({"opacity_unit": "cm"})"), inv, "config: fields[0].transfer_function.opacity_unit must be one of");
  expect_error(with_tf(R"({"colormap": "viridis"})"), inv, "config: fields[0].transfer_function.colormap is not a known key");
  expect_error(with_tf("[]"), inv, "config: fields[0].transfer_function must be an object");
  expect_error(doc(kOut, kCams, kFields, R"(, "trigger": {})"), inv, "config: trigger needs every_cycles, every_time and/or when");
  expect_error(doc(kOut, kCams, kFields, R"(, "trigger": {"every_cycles": 0})"), inv, "config: trigger.every_cycles must be in [1,");
  expect_error(doc(kOut, kCams, kFields, R"(, "trigger": {"every_time": -1})"), inv, "config: trigger.every_time must be > 0");
  expect_error(doc(kOut, kCams, kFields, R"(, "trigger": {"every_step": 1})"), inv, "config: trigger.every_step is not a known key");
  expect_error(doc(kOut, kCams, kFields, R"(, "backend": "cuda")"), inv,
               "config: backend must be one of \"cpu\", \"gpu\", \"auto\", got \"cuda\"");
  testing::TempDir dir;
  std::ofstream(dir / "array.json") << "[1, 2]";
  expect_error(dir / "array.json", inv, "config: top level must be an object");
  std::ofstream(dir / "bad.json") << "{\"output\": }";
  expect_error(dir / "bad.json", inv, "config file '" + (dir / "bad.json") + "' is not valid JSON");
}

}  // namespace
}  // namespace penumbra::insitu
