// video::VideoWriter in process: frames in, an MP4 out that FFmpeg's own
// tools read back with the frame count, size, duration and pixels written;
// bad options and unwritable paths fail with one-line errors and leave no
// file; an abandoned movie leaves nothing.
#include "relief/video/video_writer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "movie_probe.h"
#include "test_support.h"

namespace relief::testing {
namespace {

namespace fs = std::filesystem;

// Shapes drifting frame to frame, like terrain under a moving camera.
Image synthetic_frame(int width, int height, int index) {
  Image image{width, height, std::vector<uint8_t>(static_cast<size_t>(width) * height * 4)};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      uint8_t* p = &image.rgba[(static_cast<size_t>(y) * width + x) * 4];
      // Colours that change slowly (hypsometric tints, imagery) shaded by
      // fine relief: yuv420p keeps the shading and halves the colour.
      const double t = index * 0.2;
      const double shade = 0.85 + 0.15 * std::sin(x / 8.0 + t) * std::cos(y / 10.0);
      p[0] = static_cast<uint8_t>(shade * (150 + 60 * std::sin(x / 40.0 + t)));
      p[1] = static_cast<uint8_t>(shade * (130 + 60 * std::cos(y / 30.0 - t)));
      p[2] = static_cast<uint8_t>(shade * (100 + 40 * std::sin((x + y) / 50.0 + t)));
      p[3] = 255;
    }
  }
  return image;
}

bool no_files_in(const fs::path& dir) {
  return fs::is_empty(dir);
}

TEST(VideoWriter, FramesSizeDurationAndPixelsReadBack) {
  ScratchDir dir("video_writer");
  const fs::path movie = dir / "clip.mp4";
  constexpr int kWidth = 96, kHeight = 64, kFrames = 12;
  auto writer = video::VideoWriter::open(movie, kWidth, kHeight, 24, {});
  ASSERT_TRUE(writer) << writer.error().message;
  std::vector<Image> written;
  for (int i = 0; i < kFrames; ++i) {
    written.push_back(synthetic_frame(kWidth, kHeight, i));
    ASSERT_TRUE((*writer)->write(written.back().rgba));
  }
  EXPECT_FALSE(fs::exists(movie)) << "the movie appears only when finished";
  auto stats = (*writer)->finish();
  ASSERT_TRUE(stats) << stats.error().message;
  EXPECT_EQ(stats->frames, uint64_t{kFrames});
  EXPECT_EQ(stats->bytes, fs::file_size(movie));
  EXPECT_TRUE(temporary_files(dir.path()).empty());

  const MovieInfo info = probe_movie(movie);
  EXPECT_EQ(info.codec, "h264");
  EXPECT_EQ(info.pix_fmt, "yuv420p");
  EXPECT_EQ(info.width, kWidth);
  EXPECT_EQ(info.height, kHeight);
  EXPECT_EQ(info.frames, kFrames);
  EXPECT_EQ(info.frame_rate, "24/1");
  EXPECT_NEAR(info.duration, kFrames / 24.0, 1e-3);
  const std::vector<Image> decoded = decode_movie(movie, kWidth, kHeight);
  ASSERT_EQ(decoded.size(), size_t{kFrames});
  for (int i = 0; i < kFrames; ++i) EXPECT_GE(psnr(decoded[i], written[i]), 40) << "frame " << i;
}

// The preset reaches x264, which writes its settings into the stream (an SEI
// message: "x264 - core ... options: ..."): ultrafast turns CABAC off,
// veryfast (the default) searches sub-pixels at level 2, veryslow at 10. The
// frames read back as well at every preset.
TEST(VideoWriter, ThePresetReachesTheEncoder) {
  ScratchDir dir("video_writer_preset");
  constexpr int kWidth = 64, kHeight = 48, kFrames = 4;
  for (const auto& [preset, setting] :
       {std::pair{"ultrafast", "cabac=0"}, {"veryfast", "subme=2"}, {"veryslow", "subme=10"}}) {
    const fs::path movie = dir / fmt::format("{}.mp4", preset);
    video::VideoOptions options;
    if (std::string(preset) != "veryfast") options.preset = preset;  // else the default
    auto writer = video::VideoWriter::open(movie, kWidth, kHeight, 24, options);
    ASSERT_TRUE(writer) << writer.error().message;
    std::vector<Image> written;
    for (int i = 0; i < kFrames; ++i) {
      written.push_back(synthetic_frame(kWidth, kHeight, i));
      ASSERT_TRUE((*writer)->write(written.back().rgba));
    }
    ASSERT_TRUE((*writer)->finish());
    std::ifstream in(movie, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), {}};
    EXPECT_NE(bytes.find(setting), std::string::npos) << preset;
    const std::vector<Image> decoded = decode_movie(movie, kWidth, kHeight);
    ASSERT_EQ(decoded.size(), size_t{kFrames}) << preset;
    for (int i = 0; i < kFrames; ++i) EXPECT_GE(psnr(decoded[i], written[i]), 40) << preset;
  }
}

// The movie export reads frames back bottom row first (as GL stores them)
// into recycled buffers and lets the encoder flip them: the movie must be
// the one written from top-first frames. Not bit for bit: two x264 encoders
// running at once do not always make the same decisions (even on identical
// input a few hundred pixels of a frame differed by up to 6 levels), so each
// frame must match the one written, and both movies each other, at > 35 dB
// (crf 18 on frames this small: 38-45 dB); a frame upside down or a recycled
// buffer overwritten early is far below.
TEST(VideoWriter, BottomUpRowsInRecycledBuffersGiveTheSameFrames) {
  ScratchDir dir("video_writer_rows");
  constexpr int kWidth = 64, kHeight = 48, kFrames = 10;
  auto top = video::VideoWriter::open(dir / "top.mp4", kWidth, kHeight, 24, {});
  auto bottom = video::VideoWriter::open(dir / "bottom.mp4", kWidth, kHeight, 24, {});
  ASSERT_TRUE(top && bottom);
  const size_t row = size_t{kWidth} * 4;
  std::vector<Image> written;
  for (int i = 0; i < kFrames; ++i) {
    const Image& frame = written.emplace_back(synthetic_frame(kWidth, kHeight, i));
    ASSERT_TRUE((*top)->write(frame.rgba));
    std::vector<uint8_t> flipped = (*bottom)->take_buffer();
    ASSERT_EQ(flipped.size(), frame.rgba.size());
    for (int y = 0; y < kHeight; ++y) {
      std::copy_n(&frame.rgba[(kHeight - 1 - y) * row], row, &flipped[y * row]);
    }
    ASSERT_TRUE((*bottom)->write(std::move(flipped), video::RowOrder::bottom_first));
  }
  ASSERT_TRUE((*top)->finish());
  ASSERT_TRUE((*bottom)->finish());
  const std::vector<Image> a = decode_movie(dir / "top.mp4", kWidth, kHeight);
  const std::vector<Image> b = decode_movie(dir / "bottom.mp4", kWidth, kHeight);
  ASSERT_EQ(a.size(), size_t{kFrames});
  ASSERT_EQ(b.size(), size_t{kFrames});
  for (int i = 0; i < kFrames; ++i) {
    EXPECT_GE(psnr(b[i], written[static_cast<size_t>(i)]), 35) << "frame " << i;
    EXPECT_GE(psnr(a[i], b[i]), 35) << "frame " << i;
  }
}

TEST(VideoWriter, FractionalFrameRateKeepsTheDuration) {
  ScratchDir dir("video_writer_rate");
  const fs::path movie = dir / "clip.mp4";
  auto writer = video::VideoWriter::open(movie, 32, 16, 29.97, {});
  ASSERT_TRUE(writer) << writer.error().message;
  for (int i = 0; i < 30; ++i) ASSERT_TRUE((*writer)->write(synthetic_frame(32, 16, i).rgba));
  ASSERT_TRUE((*writer)->finish());
  const MovieInfo info = probe_movie(movie);
  EXPECT_EQ(info.frames, 30);
  EXPECT_NEAR(info.duration, 30 / 29.97, 2e-3);
}

TEST(VideoWriter, AbandonedMovieLeavesNothing) {
  ScratchDir dir("video_writer_abandon");
  {
    auto writer = video::VideoWriter::open(dir / "clip.mp4", 32, 16, 10, {});
    ASSERT_TRUE(writer) << writer.error().message;
    ASSERT_TRUE((*writer)->write(synthetic_frame(32, 16, 0).rgba));
  }  // destroyed without finish(): an export that failed half way
  EXPECT_TRUE(no_files_in(dir.path()));
}

TEST(VideoWriter, ReplacesAnOlderMovieOnlyWhenFinished) {
  ScratchDir dir("video_writer_replace");
  const fs::path movie = dir / "clip.mp4";
  std::ofstream(movie) << "the previous movie";
  {
    auto writer = video::VideoWriter::open(movie, 32, 16, 10, {});
    ASSERT_TRUE(writer) << writer.error().message;
    ASSERT_TRUE((*writer)->write(synthetic_frame(32, 16, 0).rgba));
  }
  EXPECT_EQ(fs::file_size(movie), std::string("the previous movie").size());
  auto writer = video::VideoWriter::open(movie, 32, 16, 10, {});
  ASSERT_TRUE(writer);
  ASSERT_TRUE((*writer)->write(synthetic_frame(32, 16, 0).rgba));
  ASSERT_TRUE((*writer)->finish());
  EXPECT_EQ(probe_movie(movie).frames, 1);
}

void expect_refused(const Result<std::unique_ptr<video::VideoWriter>>& writer,
                    const std::string& needle, const fs::path& dir) {
  ASSERT_FALSE(writer);
  EXPECT_NE(writer.error().message.find(needle), std::string::npos) << writer.error().message;
  EXPECT_EQ(writer.error().message.find('\n'), std::string::npos) << writer.error().message;
  EXPECT_TRUE(temporary_files(dir).empty());
}

TEST(VideoWriter, BadInputIsAOneLineErrorAndNoFile) {
  ScratchDir dir("video_writer_bad");
  const fs::path movie = dir / "clip.mp4";
  expect_refused(video::VideoWriter::open(movie, 33, 16, 10, {}), "33x16", dir.path());
  expect_refused(video::VideoWriter::open(movie, 32, 15, 10, {}), "even width and height",
                 dir.path());
  expect_refused(video::VideoWriter::open(movie, 32, 16, 10, {.codec = "prores"}),
                 "--codec: 'prores'", dir.path());
  expect_refused(video::VideoWriter::open(movie, 32, 16, 10, {.crf = 52}), "--crf", dir.path());
  expect_refused(video::VideoWriter::open(movie, 32, 16, 10, {.preset = "Medium"}),
                 "--preset: 'Medium'", dir.path());
  EXPECT_FALSE(fs::exists(movie));
  // Under a regular file: no directory can be made there (root ignores modes).
  std::ofstream(dir / "file") << "x";
  const fs::path unwritable = dir / "file" / "clip.mp4";
  expect_refused(video::VideoWriter::open(unwritable, 32, 16, 10, {}), unwritable.string(),
                 dir.path());
  fs::create_directory(dir / "directory.mp4");
  expect_refused(video::VideoWriter::open(dir / "directory.mp4", 32, 16, 10, {}), "directory.mp4",
                 dir.path());
}

}  // namespace
}  // namespace relief::testing
