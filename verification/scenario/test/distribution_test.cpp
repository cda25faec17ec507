#include "verification/scenario/distribution.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "config/strict_yaml.hpp"

namespace shelfcross::verification {
namespace {

Distribution parse(const std::string& yaml) {
  const auto doc = config::Document::from_string(yaml, "d.yaml");
  const config::Map root = doc.root();
  Distribution d = parse_distribution(root, "x");
  root.finish();
  return d;
}

int error_line(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const config::ConfigError& e) {
    return e.line();
  }
  return -1;
}

TEST(Distribution, ParsesEveryKind) {
  EXPECT_EQ(parse("x: {uniform: {min: 2.5, max: 3.5}}").max, 3.5);
  EXPECT_EQ(parse("x: {normal: {mean: 0.1, stddev: 0.2}}").stddev, 0.2);
  const Distribution t = parse("x: {truncated_normal: {mean: 0, stddev: 0.05, min: -0.1, max: 0.2}}");
  EXPECT_EQ(t.kind, Distribution::Kind::truncated_normal);
  EXPECT_EQ(t.lowest(), -0.1);
  const Distribution c = parse("x: {choice: {values: [0.6, 1, 1.4]}}");
  EXPECT_EQ(c.weights, (std::vector<double>{1, 1, 1}));
  EXPECT_EQ(c.highest(), 1.4);
}

TEST(Distribution, RefusesBadSpecsWithLines) {
  EXPECT_EQ(error_line("a: 1\nx: {uniform: {min: 3, max: 2}}\n"), 2);
  EXPECT_EQ(error_line("x:\n  normal: {mean: 0, stddev: -1}\n"), 2);
  EXPECT_EQ(error_line("x:\n  gamma: {k: 1}\n"), 1);
  EXPECT_EQ(error_line("x: {uniform: {min: 1, max: 2}, normal: {mean: 0, stddev: 1}}\n"), 1);
  EXPECT_EQ(error_line("x:\n  choice: {values: [1, 2], weights: [1]}\n"), 2);
  EXPECT_EQ(error_line("x:\n  uniform: {min: 1, max: 2, mode: 1.5}\n"), 2);
}

TEST(Distribution, SamplesStayInSupportWithTheRightMoments) {
  RandomStream stream(5, StreamId::dispersion);
  const Distribution tn = parse("x: {truncated_normal: {mean: 0, stddev: 1, min: -0.5, max: 2}}");
  const Distribution ch = parse("x: {choice: {values: [1, 2, 3], weights: [1, 2, 1]}}");
  const Distribution un = parse("x: {uniform: {min: 2.5, max: 3.5}}");
  double tn_sum = 0.0, ch_sum = 0.0, un_sum = 0.0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double t = tn.sample(stream);
    ASSERT_GE(t, -0.5);
    ASSERT_LE(t, 2.0);
    tn_sum += t;
    const double c = ch.sample(stream);
    ASSERT_TRUE(c == 1.0 || c == 2.0 || c == 3.0);
    ch_sum += c;
    const double u = un.sample(stream);
    ASSERT_GE(u, 2.5);
    ASSERT_LT(u, 3.5);
    un_sum += u;
  }
  // Mean of N(0,1) truncated to [a, b]: (phi(a) - phi(b)) / (Phi(b) - Phi(a)).
  const auto phi = [](double x) { return std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI); };
  const auto Phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  EXPECT_NEAR(tn_sum / n, (phi(-0.5) - phi(2.0)) / (Phi(2.0) - Phi(-0.5)), 0.01);
  EXPECT_NEAR(ch_sum / n, 2.0, 0.01);
  EXPECT_NEAR(un_sum / n, 3.0, 0.005);
}

}  // namespace
}  // namespace shelfcross::verification
