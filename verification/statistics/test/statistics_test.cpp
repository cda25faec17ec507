// Safety apart from mission success: the contact rate's one-sided Clopper-Pearson
// upper bound and the classification of run outcomes.
#include <cmath>

#include <gtest/gtest.h>

#include "verification/statistics/statistics.hpp"

namespace shelfcross::verification {
namespace {

TEST(Statistics, ClopperPearsonUpperMatchesClosedFormsAndItsDefinition) {
  // No event: p_U = 1 - alpha^(1/n): 0 in 2,995 runs bounds the probability below 0.1 %,
  // 0 in 299 below 1 %.
  EXPECT_NEAR(clopper_pearson_upper(0, 2995), 1.0 - std::pow(0.05, 1.0 / 2995.0), 1e-12);
  EXPECT_LT(clopper_pearson_upper(0, 2995), 0.001);
  EXPECT_LT(clopper_pearson_upper(0, 299), 0.01);
  EXPECT_GT(clopper_pearson_upper(0, 298), 0.01 - 1e-4);
  EXPECT_EQ(clopper_pearson_upper(10, 10), 1.0);
  // Symmetry with the lower bound: upper(k, n) = 1 - lower(n - k, n).
  EXPECT_NEAR(clopper_pearson_upper(3, 48), 1.0 - clopper_pearson_lower(45, 48), 1e-12);
  // The defining equation P(X <= k | p_U) = alpha, X ~ Bin(n, p_U).
  const int n = 48, k = 1;
  const double p = clopper_pearson_upper(k, n);
  double cdf = 0.0;
  for (int x = 0; x <= k; ++x) {
    cdf += std::exp(std::lgamma(n + 1.0) - std::lgamma(x + 1.0) - std::lgamma(n - x + 1.0) + x * std::log(p) +
                    (n - x) * std::log1p(-p));
  }
  EXPECT_NEAR(cdf, 0.05, 1e-9);
  EXPECT_THROW(clopper_pearson_upper(3, 2), std::invalid_argument);
  EXPECT_THROW(clopper_pearson_upper(0, 0), std::invalid_argument);
}

TEST(Statistics, SafetyCountsContactsApartFromAbortsAndInventoryErrors) {
  const SafetySummary s = summarize_safety({"success", "collision", "left_arena", "mission_aborted", "no_crossing",
                                            "inventory_mismatch", "timeout", "flight_software_exception", "success"});
  EXPECT_EQ(s.runs, 9);
  EXPECT_EQ(s.contacts, 2);
  EXPECT_EQ(s.shelf_contacts, 1);
  EXPECT_EQ(s.safe_aborts, 2);
  EXPECT_EQ(s.inventory_errors, 1);
  EXPECT_EQ(s.other_failures, 2);
  EXPECT_DOUBLE_EQ(s.contact_rate, 2.0 / 9.0);
  EXPECT_DOUBLE_EQ(s.contact_upper_95, clopper_pearson_upper(2, 9));
  const SafetySummary none = summarize_safety({});
  EXPECT_EQ(none.runs, 0);
  EXPECT_EQ(none.contact_upper_95, 1.0);  // no run says nothing
}

}  // namespace
}  // namespace shelfcross::verification
