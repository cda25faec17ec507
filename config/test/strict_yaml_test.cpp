#include "config/strict_yaml.hpp"

#include <gtest/gtest.h>

namespace shelfcross::config {
namespace {

// Reads a document and returns the error it raises (file, line, reason), or fails.
ConfigError error_of(const std::string& text, const std::function<void(const Map&)>& read) {
  try {
    const Document doc = Document::from_string(text, "test.yaml");
    read(doc.root());
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no error raised for:\n" << text;
  return ConfigError("", 0, "");
}

TEST(StrictYaml, ReadsTypedValuesDefaultsAndNestedSections) {
  const Document doc = Document::from_string(
      "speed_mps: 1.5\nruns: 12\nname: shelf\nverbose: true\nsizes: [0.34, 0.48]\n"
      "camera:\n  fx: 921.17\n",
      "t.yaml");
  const Map root = doc.root();
  EXPECT_DOUBLE_EQ(root.required<double>("speed_mps", {.min = 0.0, .max = 8.0}), 1.5);
  EXPECT_EQ(root.required<int>("runs"), 12);
  EXPECT_EQ(root.required<std::string>("name"), "shelf");
  EXPECT_TRUE(root.required<bool>("verbose"));
  EXPECT_EQ(root.optional<int>("jobs", 4), 4);
  EXPECT_EQ(root.required_list<double>("sizes", {}, 2), (std::vector<double>{0.34, 0.48}));
  const Map cam = root.map("camera");
  EXPECT_DOUBLE_EQ(cam.required<double>("fx"), 921.17);
  EXPECT_NO_THROW(cam.finish());
  EXPECT_NO_THROW(root.finish());
}

TEST(StrictYaml, RefusesUnknownKeyWithItsLine) {
  const ConfigError e = error_of("a: 1\nb: 2\nspeeed: 3\n", [](const Map& m) {
    m.required<int>("a");
    m.required<int>("b");
    m.finish();
  });
  EXPECT_EQ(e.file(), "test.yaml");
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.reason().find("unknown key 'speeed'"), std::string::npos);
  EXPECT_NE(std::string(e.what()).find("test.yaml:3:"), std::string::npos);
}

TEST(StrictYaml, RefusesAKeyGivenTwiceAtItsSecondLine) {
  // One of the two values would otherwise be silently ignored.
  const ConfigError e = error_of("camera:\n  width_px: 960\n  height_px: 720\n  width_px: 961\n", [](const Map& m) {
    const Map cam = m.map("camera");
    cam.required<int>("width_px");
  });
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(e.reason().find("key 'width_px' given twice (first on line 2)"), std::string::npos) << e.reason();
  // At the top level too.
  const ConfigError top = error_of("a: 1\nb: 2\na: 3\n", [](const Map& m) { m.required<int>("a"); });
  EXPECT_EQ(top.line(), 3);
}

TEST(StrictYaml, RefusesWrongTypes) {
  EXPECT_EQ(error_of("a: 1\nspeed: fast\n", [](const Map& m) { m.required<double>("speed"); }).line(), 2);
  EXPECT_EQ(error_of("n: 1.5\n", [](const Map& m) { m.required<int>("n"); }).line(), 1);
  EXPECT_EQ(error_of("\n\nflag: 3\n", [](const Map& m) { m.required<bool>("flag"); }).line(), 3);
  EXPECT_EQ(error_of("x: [1, 2]\n", [](const Map& m) { m.required<double>("x"); }).line(), 1);
  EXPECT_EQ(error_of("x: .nan\n", [](const Map& m) { m.required<double>("x"); }).line(), 1);
  EXPECT_EQ(error_of("s:\n  - 1\n  - oops\n", [](const Map& m) { m.required_list<double>("s"); })
                .line(), 3);
  EXPECT_EQ(error_of("sec: 5\n", [](const Map& m) { m.map("sec"); }).line(), 1);
}

TEST(StrictYaml, RefusesMissingRequiredAndOutOfRange) {
  const ConfigError missing = error_of("a: 1\n", [](const Map& m) { m.required<double>("b"); });
  EXPECT_NE(missing.reason().find("missing required key 'b'"), std::string::npos);
  const ConfigError range =
      error_of("a: 1\nmass_kg: -0.08\n", [](const Map& m) { m.required<double>("mass_kg", {.min = 0.0, .min_exclusive = true}); });
  EXPECT_EQ(range.line(), 2);
  EXPECT_NE(range.reason().find("out of range"), std::string::npos);
  const ConfigError size =
      error_of("v: [1, 2]\n", [](const Map& m) { m.required_list<double>("v", {}, 3); });
  EXPECT_NE(size.reason().find("list of 3"), std::string::npos);
}

TEST(StrictYaml, ReportsSyntaxErrorsAndMissingFiles) {
  EXPECT_GT(error_of("a: [1, 2\nb: 3\n", [](const Map&) {}).line(), 0);
  EXPECT_THROW(Document::from_file("/nonexistent/shelfcross.yaml"), ConfigError);
  EXPECT_THROW(Document::from_string("", "empty.yaml"), ConfigError);
}

}  // namespace
}  // namespace shelfcross::config
