// A run record survives its trip through an MPI message bit for bit (the coordinator stores
// exactly what the worker computed), and a malformed message is an error, not a crash.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "distributed/mpi_campaign.hpp"

namespace shelfcross::distributed {
namespace {

TEST(RecordMessage, RoundTripsExactly) {
  const verification::RunRecord r{
      123456789012345,
      std::numeric_limits<std::uint64_t>::max() - 7,
      R"({"mass_kg":0.08700000000000001})",
      "collision",
      R"({"detail":"hit \"shelf\"\n","min_clearance_m":-0.0})",
      "0123456789abcdef0123456789abcdef",
      std::nextafter(0.1, 1.0),
      std::string("{\"t\":[0.1]}") + std::string(1, '\0') + "\xc3\xa9",
      std::nextafter(2.5, 0.0)};
  EXPECT_EQ(decode_record(encode_record(r)), r);
  // A lost run's record: no CPU figure, and none it comes back with.
  verification::RunRecord lost = r;
  lost.cpu_s.reset();
  EXPECT_EQ(decode_record(encode_record(lost)), lost);
}

TEST(RecordMessage, CpuSecondsAreANumberAtLeastZeroOrNull) {
  const std::string fields = R"("index":1,"seed":2,"dispersion_json":"{}","outcome":"success","metrics_json":"{}",)"
                             R"("run_hash":"","wall_s":0.5,"trace_json":"{}")";
  EXPECT_EQ(decode_record("{" + fields + R"(,"cpu_s":0.25})").cpu_s, 0.25);
  EXPECT_EQ(decode_record("{" + fields + R"(,"cpu_s":null})").cpu_s, std::nullopt);
  EXPECT_THROW(decode_record("{" + fields + "}"), std::invalid_argument);  // every sender writes it
  EXPECT_THROW(decode_record("{" + fields + R"(,"cpu_s":-0.25})"), std::invalid_argument);
  EXPECT_THROW(decode_record("{" + fields + R"(,"cpu_s":"0.25"})"), std::invalid_argument);
  EXPECT_THROW(decode_record("{" + fields + R"(,"cpu_s":true})"), std::invalid_argument);
}

TEST(RecordMessage, MalformedIsAnError) {
  EXPECT_THROW(decode_record("{"), std::invalid_argument);
  EXPECT_THROW(decode_record(R"({"index": 1})"), std::invalid_argument);
  EXPECT_THROW(decode_record(R"({"index":"x","seed":1,"dispersion_json":"","outcome":"","metrics_json":"",)"
                             R"("run_hash":"","wall_s":0,"trace_json":""})"),
               std::invalid_argument);
}

TEST(MpiLauncher, DetectedFromItsEnvironment) {
  unsetenv("OMPI_COMM_WORLD_SIZE");
  unsetenv("PMIX_RANK");
  unsetenv("PMI_SIZE");
  EXPECT_FALSE(launched_by_mpi());
  setenv("OMPI_COMM_WORLD_SIZE", "3", 1);
  EXPECT_TRUE(launched_by_mpi());
  unsetenv("OMPI_COMM_WORLD_SIZE");
}

}  // namespace
}  // namespace shelfcross::distributed
