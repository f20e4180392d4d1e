// The seeds of fuzz_messages (tests/fuzz/corpus/fuzz_messages): for each type of fuzz_types.hpp
// a message with every field zero, and a small depth frame in each encoding, each file the
// type's index byte and the encoded message.
//   fuzz_seeds --write DIR   writes them;
//   fuzz_seeds --check DIR   exits 1 naming the first seed missing or not as written now (a
//                            message type changed: run --write and commit the seeds).
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "bus/depth_codec.hpp"
#include "fuzz_types.hpp"

namespace {

using Seed = std::pair<std::string, std::vector<uint8_t>>;

template <class T>
std::vector<uint8_t> encoded(std::size_t index, const T& msg) {
  std::vector<uint8_t> bytes(1 + static_cast<std::size_t>(msg.getEncodedSize()));
  bytes[0] = static_cast<uint8_t>(index);
  msg.encode(bytes.data(), 1, static_cast<int>(bytes.size() - 1));
  return bytes;
}

template <class... T>
void add_zero_messages(pbnbv::fuzz::Types<T...>, std::vector<Seed>& seeds) {
  std::size_t k = 0;
  ((seeds.emplace_back(std::to_string(k) + "-" + T::getTypeName() + "-zero.bin", encoded(k, T{})), ++k), ...);
}

// A 4 x 3 frame of 0.5 m (5000 counts of 0.1 mm), raw or zlib; index 3 is depth_frame_t.
std::vector<uint8_t> small_frame(bool zlib) {
  pbnbv::depth_frame_t f{};
  f.camera_id = "pbnbv-twin";
  f.seq = 7;
  f.trigger_seq = 7;
  f.scan_id = "fuzz";
  f.width = 4;
  f.height = 3;
  f.fx = f.fy = 4;
  f.cx = 1.5;
  f.cy = 1;
  f.depth_min_m = 0.1;
  f.depth_max_m = 2;
  f.depth_unit_m = 1e-4;
  std::vector<uint8_t> raw;
  for (int i = 0; i < 12; ++i) {
    raw.push_back(5000 & 0xff);
    raw.push_back(5000 >> 8);
  }
  f.encoding = zlib ? pbnbv::depth_frame_t::kEncodingZlib : pbnbv::depth_frame_t::kEncodingRaw;
  f.depth = zlib ? pbnbv::bus::deflate_bytes(raw) : raw;
  f.num_bytes = static_cast<int32_t>(f.depth.size());
  return encoded(3, f);
}

std::vector<Seed> seeds() {
  std::vector<Seed> s;
  add_zero_messages(pbnbv::fuzz::kTypes, s);
  s.emplace_back("3-depth_frame_t-4x3-raw.bin", small_frame(false));
  s.emplace_back("3-depth_frame_t-4x3-zlib.bin", small_frame(true));
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc == 3 ? argv[1] : "";
  if (mode != "--write" && mode != "--check") {
    std::fprintf(stderr, "usage: fuzz_seeds --write DIR | --check DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[2];
  if (mode == "--write") std::filesystem::create_directories(dir);
  for (const auto& [name, bytes] : seeds()) {
    const std::filesystem::path p = dir / name;
    if (mode == "--write") {
      std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                               static_cast<std::streamsize>(bytes.size()));
      continue;
    }
    std::ifstream in(p, std::ios::binary);
    const std::vector<uint8_t> have((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) {
      std::fprintf(stderr, "fuzz_seeds: %s is missing (run fuzz_seeds --write %s)\n", p.c_str(), dir.c_str());
      return 1;
    }
    if (have != bytes) {
      std::fprintf(stderr, "fuzz_seeds: %s is not the message as encoded now (a message type changed? run fuzz_seeds --write %s and commit)\n",
                   p.c_str(), dir.c_str());
      return 1;
    }
  }
  std::printf("fuzz_seeds: %zu seeds in %s match the contract\n", seeds().size(), dir.c_str());
  return 0;
}
