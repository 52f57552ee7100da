// Writes the recording fuzzer's seeds (recording_fuzz.cpp) into the folder named by its argument:
// small recordings as the firmware's recording output writes them (zstd chunks, summary), of
// raw left and right images in mono8 and rgb8, with other topics beside them.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "epipole/core/cdr_writer.hpp"
#include "epipole/core/mcap_writer.hpp"

namespace {

using epipole::cdr::CdrWriter;

void image(std::vector<std::uint8_t>& out, int stamp, const std::string& encoding, int width,
           int height) {
  CdrWriter w(out);
  w.i32(stamp);
  w.u32(0);
  w.string("cam");
  w.u32(static_cast<std::uint32_t>(height));
  w.u32(static_cast<std::uint32_t>(width));
  w.string(encoding);
  w.u8(0);
  const int channels = encoding == "mono8" ? 1 : 3;
  w.u32(static_cast<std::uint32_t>(width * channels));
  std::uint8_t* pixels = w.byte_sequence(static_cast<std::size_t>(width * height * channels));
  for (int i = 0; i < width * height * channels; ++i) {
    pixels[i] = static_cast<std::uint8_t>(i * 37 + stamp);
  }
}

void write(const std::filesystem::path& file, const std::string& encoding, int pairs) {
  epipole::mcap::Writer w({{"sensor_msgs/msg/Image", "ros2msg", "uint8[] data\n"}},
                          {{1, "/epipole/left/image_raw", "cdr", {}},
                           {1, "/epipole/right/image_raw", "cdr", {}},
                           {1, "/epipole/left/image_rect", "cdr", {}}},
                          512, 512);
  w.open(file, "recording_fuzz_seeds");
  for (int i = 0; i < pairs; ++i) {
    for (std::uint16_t channel = 0; channel < 3; ++channel) {
      image(w.begin_message(channel, static_cast<std::uint32_t>(i),
                            static_cast<std::uint64_t>(i) * 1000, 0),
            i, encoding, 6 + channel % 2, 4);
      w.end_message();
    }
  }
  w.close();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: recording_fuzz_seeds FOLDER\n");
    return 2;
  }
  const std::filesystem::path folder = argv[1];
  std::filesystem::create_directories(folder);
  for (const char* name : {"mono8.mcap", "rgb8.mcap"}) std::filesystem::remove(folder / name);
  write(folder / "mono8.mcap", "mono8", 3);
  write(folder / "rgb8.mcap", "rgb8", 2);
  return 0;
}
