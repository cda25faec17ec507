// The simulated Tello's encoder: the default backend's stream is the one every run uses; the
// hardware backend (NVENC) either opens and makes the same kind of stream, or refuses clearly.
#include "verification/world/h264_encoder.hpp"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "flight_sw/tello/h264_decoder.hpp"
#include "sdk/video_framing.hpp"

namespace shelfcross::verification {
namespace {

constexpr int kWidth = 320, kHeight = 240;

// Frame k: a gradient with a square sliding right, so P-frames carry motion.
cv::Mat moving_square(int k) {
  cv::Mat f(kHeight, kWidth, CV_8UC3);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) f.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(x / 2), static_cast<uchar>(y), 90);
  }
  cv::rectangle(f, cv::Rect(20 + 8 * k, 60, 60, 60), cv::Scalar(240, 240, 240), cv::FILLED);
  return f;
}

std::vector<std::string> encode_frames(H264Encoder& encoder, int frames) {
  std::vector<std::string> out;
  for (int k = 0; k < frames; ++k) out.push_back(encoder.encode(moving_square(k), k % 4 == 0));
  return out;
}

TEST(H264Encoder, ExplicitLibx264IsTheDefaultStreamByteForByte) {
  H264Encoder by_default(kWidth, kHeight, 30, 8, H264Encoder::kTelloQp, 3);
  H264Encoder explicit_x264(kWidth, kHeight, 30, 8, H264Encoder::kTelloQp, 3, H264Encoder::Backend::Libx264);
  EXPECT_EQ(encode_frames(by_default, 6), encode_frames(explicit_x264, 6));
}

// Without an NVIDIA GPU and driver the constructor must throw std::runtime_error naming NVENC;
// with one, the stream must be Tello-like: one access unit per frame, SPS and PPS before every
// forced key frame (an IDR), and pictures the flight software's decoder reads back.
TEST(H264Encoder, NvencOpensOrRefusesNamingNvenc) {
  std::unique_ptr<H264Encoder> encoder;
  try {
    encoder = std::make_unique<H264Encoder>(kWidth, kHeight, 30, 8, H264Encoder::kTelloQp, 3,
                                            H264Encoder::Backend::Nvenc);
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("NVENC"), std::string::npos) << e.what();
    GTEST_SKIP() << e.what();
  }
  tello::H264Decoder decoder;
  for (int k = 0; k < 9; ++k) {
    const cv::Mat source = moving_square(k);
    const std::string au = encoder->encode(source, k % 4 == 0);
    const std::vector<int> types = sdk::nal_unit_types(au);
    ASSERT_FALSE(types.empty()) << "frame " << k;
    if (k % 4 == 0) {
      EXPECT_EQ(types.front(), 7) << "frame " << k << ": a key frame starts with its SPS";
      EXPECT_NE(std::find(types.begin(), types.end(), 5), types.end()) << "frame " << k << ": no IDR slice";
    }
    const tello::DecodeResult r = decoder.decode(au);
    EXPECT_EQ(r.pictures, 1) << "frame " << k;
    EXPECT_FALSE(r.error) << "frame " << k;
    cv::Mat decoded;
    ASSERT_TRUE(decoder.latest_bgr(decoded));
    EXPECT_GT(tello::psnr_db(decoded, source), 30.0) << "frame " << k;
  }
}

}  // namespace
}  // namespace shelfcross::verification
