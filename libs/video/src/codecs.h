#pragma once
// The codecs --codec may name and the FFmpeg encoder of each; shared by the
// option check (libs/video) and the encoder module.
namespace relief::video {

struct CodecName {
  const char* name;
  const char* encoder;
};
inline constexpr CodecName kCodecs[] = {{"h264", "libx264"}};

// libx264's presets, fastest first.
inline constexpr const char* kPresets[] = {"ultrafast", "superfast", "veryfast", "faster",  "fast",
                                           "medium",    "slow",      "slower",   "veryslow"};

}  // namespace relief::video
