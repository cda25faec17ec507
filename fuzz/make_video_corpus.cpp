// Writes the video receiver's seed corpus (fuzz/corpus/video_receiver/): short Tello-like
// H.264 streams from the simulated Tello's encoder, cut into datagrams as the drone sends them
// (sdk::tello_datagrams), in video_receiver_fuzz.cpp's input format (per datagram a 2-byte
// big-endian header: top bit "from a foreign sender", 15 bits length; then its bytes), clean
// and damaged. Run once; the files are committed (fuzz/README.md):
//   cmake --build --preset fuzz --target make_video_corpus && build/fuzz/fuzz/make_video_corpus fuzz/corpus/video_receiver
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "sdk/video_framing.hpp"
#include "verification/world/h264_encoder.hpp"

using namespace shelfcross;
using Datagrams = std::vector<std::string>;

namespace {

/// Frames of a moving scene: a gradient, a textured patch, a box that slides.
std::vector<Datagrams> stream(int w, int h, int frames, int key_interval, int slices) {
  verification::H264Encoder encoder(w, h, 30, key_interval, 30, slices);
  cv::RNG rng(7);
  std::vector<Datagrams> out;
  for (int f = 0; f < frames; ++f) {
    cv::Mat bgr(h, w, CV_8UC3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(x * 255 / w, y * 255 / h, (x + y + 8 * f) & 255);
    cv::Mat patch = bgr(cv::Rect(w / 8, h / 8, w / 3, h / 3));
    rng.fill(patch, cv::RNG::UNIFORM, 0, 255);
    cv::rectangle(bgr, cv::Rect(8 + 6 * f, h / 2, w / 5, h / 4), cv::Scalar(0, 0, 255), cv::FILLED);
    out.push_back(sdk::tello_datagrams(encoder.encode(bgr)));
  }
  return out;
}

void put(std::string& file, const std::string& d, bool foreign = false) {
  const unsigned n = static_cast<unsigned>(d.size()) | (foreign ? 0x8000u : 0u);
  file += static_cast<char>(n >> 8);
  file += static_cast<char>(n & 0xff);
  file += d;
}

void write(const std::string& dir, const std::string& name, const std::string& bytes) {
  std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
  std::printf("%s: %zu bytes\n", name.c_str(), bytes.size());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_video_corpus <folder>\n");
    return 2;
  }
  const std::string dir = argv[1];
  const auto small = stream(160, 120, 6, 3, 1);
  const auto sliced = stream(320, 240, 4, 2, 4);
  std::string clean, sliced_file, lost, truncated, foreign, reordered, no_key;
  for (const Datagrams& f : small)
    for (const std::string& d : f) put(clean, d);
  for (const Datagrams& f : sliced)
    for (const std::string& d : f) put(sliced_file, d);
  for (size_t i = 0; i < sliced.size(); ++i)
    for (size_t j = 0; j < sliced[i].size(); ++j) {
      if (!(i == 0 && j == sliced[0].size() / 2)) put(lost, sliced[i][j]);       // a datagram lost mid key frame
      if (!(i == 1 && j + 1 == sliced[1].size())) put(truncated, sliced[i][j]);  // a frame's short end lost
      put(foreign, sliced[i][j]);
      if (j == 1) put(foreign, sliced[i][j], true);  // a stranger's copy
    }
  put(foreign, std::string());  // an empty datagram
  for (size_t i = 0; i < sliced.size(); ++i) {
    Datagrams f = sliced[i];
    if (f.size() > 3) std::swap(f[f.size() - 2], f[f.size() - 3]);  // two datagrams swapped
    for (const std::string& d : f) put(reordered, d);
  }
  for (size_t i = 1; i < small.size(); ++i)
    if (i % 3 != 0)
      for (const std::string& d : small[i]) put(no_key, d);  // only predicted frames
  write(dir, "clean_160x120_6_frames", clean);
  write(dir, "clean_320x240_4_slices", sliced_file);
  write(dir, "lost_datagram_in_key_frame", lost);
  write(dir, "lost_frame_end", truncated);
  write(dir, "foreign_sender_and_empty", foreign);
  write(dir, "reordered_datagrams", reordered);
  write(dir, "no_key_frame", no_key);
  return 0;
}
