// Where a damaged picture is damaged, checked against the truth: one Tello-like stream
// (libx264 as tello-sim encodes it, 45 slices, cut into 1460-byte datagrams) through two video
// receivers, one that gets every datagram and one that loses a seeded share of them. Every
// row a lossy picture does not mark damaged (VideoFrame::damaged_rows) must be byte-identical
// to the loss-free picture: the damage may be over-stated, never under-stated.
#include <algorithm>
#include <iostream>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "flight_sw/tello/clock.hpp"
#include "flight_sw/tello/datagram_channel.hpp"
#include "flight_sw/tello/video_receiver.hpp"
#include "sdk/video_framing.hpp"
#include "shelfcross/random.hpp"
#include "verification/world/h264_encoder.hpp"

namespace shelfcross::tello {
namespace {

constexpr int kWidth = 960;
constexpr int kHeight = 720;

// Frame k of a scene that moves the way a camera approaching a shelf does: a textured wall
// drifting down and sideways, slowly growing coloured blocks, and a fast object, so that motion
// vectors carry damage across rows.
cv::Mat scene(int k) {
  static const cv::Mat texture = [] {
    cv::Mat t(kHeight + 200, kWidth + 200, CV_8UC3);
    RandomStream rng(11, StreamId::render_noise);
    for (int y = 0; y < t.rows; ++y) {
      for (int x = 0; x < t.cols; ++x) {
        const int n = static_cast<int>(rng.below(40));
        t.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(50 + x / 9 + n), static_cast<uchar>(70 + y / 7 + n),
                                          static_cast<uchar>(100 + (x + y) / 20 + n));
      }
    }
    return t;
  }();
  cv::Mat f = texture(cv::Rect(100 + (k * 3) % 90, 100 - (k * 2) % 90, kWidth, kHeight)).clone();
  for (int i = 0; i < 6; ++i) {
    const int s = 60 + k + 10 * i;
    cv::rectangle(f, cv::Rect(40 + 150 * i, 150 + 70 * (i % 3) + k, s, s),
                  cv::Scalar(30 * i, 200 - 20 * i, 40 + 30 * i), cv::FILLED);
  }
  cv::circle(f, cv::Point(100 + (17 * k) % 760, 600 - (11 * k) % 500), 35, cv::Scalar(0, 0, 255), cv::FILLED);
  return f;
}

struct Receiver {
  ManualClock clock{0};
  MemoryChannel* channel = nullptr;
  std::unique_ptr<VideoReceiver> receiver;
  Receiver() {
    VideoReceiverConfig c;
    c.drone_ip = "10.0.0.1";
    c.threaded = false;
    auto ch = std::make_unique<MemoryChannel>(Endpoint{"10.0.0.2", 11111});
    channel = ch.get();
    receiver = std::make_unique<VideoReceiver>(c, clock, std::move(ch));
  }
  void deliver(const std::string& d) { channel->deliver({d, Endpoint{"10.0.0.1", 62512}}); }
};

struct Tally {
  int pictures = 0, damaged = 0, whole_height = 0, rows = 0, violations = 0;
};

// Streams `frames` pictures losing datagrams with probability `loss`; checks every picture
// handed over by the lossy receiver against the loss-free one.
Tally stream(double loss, int frames, std::uint64_t seed) {
  verification::H264Encoder encoder(kWidth, kHeight, 30, 30, verification::H264Encoder::kTelloQp, 45);
  Receiver clean, lossy;
  RandomStream drops(seed, StreamId::link_faults);
  Tally t;
  for (int k = 0; k < frames; ++k) {
    for (const std::string& d : sdk::tello_datagrams(encoder.encode(scene(k)))) {
      clean.deliver(d);
      if (!drops.bernoulli(loss)) lossy.deliver(d);
    }
    clean.receiver->service();
    lossy.receiver->service();
    std::optional<VideoFrame> a = clean.receiver->take_latest();
    std::optional<VideoFrame> b = lossy.receiver->take_latest();
    if (!a || !b || a->index != b->index) continue;  // not the same picture (a lost frame end)
    EXPECT_FALSE(a->damaged);
    ++t.pictures;
    if (!b->damaged) {
      EXPECT_TRUE(b->damaged_rows.empty());
    } else {
      ++t.damaged;
      EXPECT_FALSE(b->damaged_rows.empty());
      if (b->damaged_rows.size() == 1 && b->damaged_rows[0] == RowSpan{0, kHeight}) ++t.whole_height;
    }
    std::vector<bool> marked(kHeight, false);
    for (const RowSpan& r : b->damaged_rows) {
      for (int v = r.v_begin_px; v < r.v_end_px; ++v) marked[static_cast<std::size_t>(v)] = true;
      t.rows += r.v_end_px - r.v_begin_px;
    }
    for (int v = 0; v < kHeight; ++v) {
      if (marked[static_cast<std::size_t>(v)]) continue;
      if (cv::norm(a->bgr.row(v), b->bgr.row(v), cv::NORM_INF) != 0) {
        ++t.violations;
        {
          std::cerr << "differing rows:";
          int prev = -2;
          for (int u = 0; u < kHeight; ++u) {
            if (cv::norm(a->bgr.row(u), b->bgr.row(u), cv::NORM_INF) == 0) continue;
            if (u != prev + 1) std::cerr << " " << u;
            prev = u;
            if (u + 1 == kHeight || cv::norm(a->bgr.row(u + 1), b->bgr.row(u + 1), cv::NORM_INF) == 0) std::cerr << "-" << u;
          }
          std::cerr << "\n";
        }
        ADD_FAILURE() << "loss " << loss << ", picture " << b->index << ": row " << v
                      << " differs from the loss-free picture but is not marked damaged";
        break;
      }
    }
  }
  std::cout << "loss " << loss << ": " << t.pictures << " pictures compared, " << t.damaged << " damaged ("
            << t.whole_height << " all rows), mean damaged rows per damaged picture "
            << (t.damaged ? static_cast<double>(t.rows) / t.damaged : 0.0) << " of " << kHeight << "\n";
  return t;
}

TEST(PictureDamage, RowsOutsideTheDamageAreTheLossFreePicture) {
  int damaged = 0, whole_height = 0;
  for (const double loss : {0.01, 0.03, 0.05}) {
    const Tally t = stream(loss, 150, 17);
    EXPECT_EQ(t.violations, 0);
    EXPECT_GT(t.damaged, 10) << loss;  // the check saw damage
    damaged += t.damaged;
    whole_height += t.whole_height;
  }
  EXPECT_LT(whole_height, damaged);  // and placed some of it
}

}  // namespace
}  // namespace shelfcross::tello
