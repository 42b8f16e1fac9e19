// pectus::Results: the order of the values, replacement, and the JSON the adapter base writes (escaping, doubles
// that read back to the same bits, null for what is not finite, places as arrays).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include "pectus/results.h"

using pectus::Results;

TEST(Results, KeepsTheOrderSetAndReplacesInPlace) {
  Results r;
  r.set("force_N", 14.41);
  r.set("solves", 7);
  r.set("max_stress_where", "sternum");
  r.set("max_stress_at_mm", Results::Vec3{1, 2, 3});
  r.set("solves", std::size_t(9));  // replaced, keeps its place
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r.entries()[0].key, "force_N");
  EXPECT_EQ(r.entries()[1].key, "solves");
  EXPECT_EQ(std::get<long long>(r.entries()[1].value), 9);
  EXPECT_EQ(r.entries()[2].key, "max_stress_where");
  EXPECT_EQ(r.entries()[3].key, "max_stress_at_mm");
  EXPECT_DOUBLE_EQ(r.number("force_N"), 14.41);
  EXPECT_DOUBLE_EQ(r.number("solves"), 9.0);
  EXPECT_THROW(r.number("max_stress_where"), std::out_of_range);
  EXPECT_THROW(r.number("missing"), std::out_of_range);
  EXPECT_TRUE(r.has("max_stress_at_mm"));
  EXPECT_FALSE(r.has("missing"));
  // a key may change its kind
  r.set("force_N", "n/a");
  EXPECT_EQ(std::get<std::string>(*r.find("force_N")), "n/a");
  EXPECT_EQ(r.size(), 4u);
}

TEST(Results, Json) {
  Results r;
  r.set("force_N", 14.5);
  r.set("tets", 12345);
  r.set("element", "TET10");
  r.set("at_mm", Results::Vec3{-1.5, 0, 2.25});
  r.set("whole", 3.0f);
  EXPECT_EQ(r.toJson(),
            R"({"force_N": 14.5, "tets": 12345, "element": "TET10", "at_mm": [-1.5, 0.0, 2.25], "whole": 3.0})");
  EXPECT_EQ(Results().toJson(), "{}");
}

TEST(Results, JsonEscapesTexts) {
  EXPECT_EQ(Results::jsonString(R"(a "b" \c)"), R"("a \"b\" \\c")");
  EXPECT_EQ(Results::jsonString("line\nnext\ttab\r\b\f"), R"("line\nnext\ttab\r\b\f")");
  EXPECT_EQ(Results::jsonString(std::string("nul\0x", 5)), R"("nul\u0000x")");
  EXPECT_EQ(Results::jsonString("\x01\x1f\x7f"), R"("\u0001\u001f\u007f")");
  EXPECT_EQ(Results::jsonString("costal cartilage, 5° \xE2\x80\x93 left"), "\"costal cartilage, 5° \xE2\x80\x93 left\"");
  Results r;
  r.set("a\"key", "v");
  EXPECT_EQ(r.toJson(), R"({"a\"key": "v"})");
}

TEST(Results, JsonNumbersReadBackToTheSameDouble) {
  const double values[] = {0.1, 1.0 / 3.0, 14.41, -2.5e-300, 6.02214076e23, 123456789.123456789,
                           std::numeric_limits<double>::min(), std::numeric_limits<double>::max(),
                           std::numeric_limits<double>::denorm_min(), -0.0, 1e16, 4.4703820000000001};
  for (const double v : values) {
    const std::string s = Results::jsonNumber(v);
    EXPECT_NE(s.find_first_of(".eE"), std::string::npos) << s;
    const double back = std::strtod(s.c_str(), nullptr);
    EXPECT_EQ(std::memcmp(&back, &v, sizeof v), 0) << s;
  }
}

TEST(Results, NotFiniteIsNull) {
  Results r;
  r.set("nan", std::numeric_limits<double>::quiet_NaN());
  r.set("inf", std::numeric_limits<double>::infinity());
  r.set("at", Results::Vec3{0, std::nan(""), 1});
  EXPECT_EQ(r.toJson(), R"({"nan": null, "inf": null, "at": [0.0, null, 1.0]})");
}

TEST(Results, Text) {
  Results r;
  r.set("force_N", 14.412345678);
  r.set("solves", 7);
  r.set("where", "sternum");
  r.set("at_mm", Results::Vec3{1, 2.5, -3});
  EXPECT_EQ(r.toText(), R"(force_N = 14.4123, solves = 7, where = "sternum", at_mm = (1, 2.5, -3))");
}
