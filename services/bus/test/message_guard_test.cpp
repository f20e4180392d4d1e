// The message guard (bus/message_guard.hpp) for every type of the contract: a valid message passes
// and decodes to the same bytes; every shorter prefix, every length set beyond the bytes that
// remain, and thousands of random bodies are refused before any decoder runs (and whatever it
// passes decodes). Then the attacks of issue 23: a 100-byte DEPTH_FRAME claiming 2 GB, on the bus,
// and a zlib bomb.
#include <gtest/gtest.h>
#include <zlib.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "bus/bus.hpp"
#include "bus/convert.hpp"
#include "bus/message_guard.hpp"
#include "bus/message_schema.hpp"
#include "pbnbv/arm_command_t.hpp"
#include "pbnbv/arm_status_t.hpp"
#include "pbnbv/capture_request_t.hpp"
#include "pbnbv/depth_frame_t.hpp"
#include "pbnbv/depth_trigger_t.hpp"
#include "pbnbv/ellipsoid_set_t.hpp"
#include "pbnbv/ellipsoid_t.hpp"
#include "pbnbv/heartbeat_t.hpp"
#include "pbnbv/mesh_request_t.hpp"
#include "pbnbv/mesh_result_t.hpp"
#include "pbnbv/move_request_t.hpp"
#include "pbnbv/move_result_t.hpp"
#include "pbnbv/plan_request_t.hpp"
#include "pbnbv/point_cloud_t.hpp"
#include "pbnbv/pose_t.hpp"
#include "pbnbv/registered_cloud_t.hpp"
#include "pbnbv/scan_status_t.hpp"
#include "pbnbv/stop_request_t.hpp"
#include "pbnbv/turntable_command_t.hpp"
#include "pbnbv/turntable_status_t.hpp"
#include "pbnbv/view_plan_t.hpp"
#include "pbnbv/voxel_set_t.hpp"

// Bytes allocated while `counting` is set: the guard must not allocate from a message's counts.
namespace {
std::atomic<bool> counting{false};
std::atomic<std::size_t> allocated_bytes{0}, largest_allocation{0};
}  // namespace

void* operator new(std::size_t n) {
  if (counting) {
    allocated_bytes += n;
    if (n > largest_allocation) largest_allocation = n;
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace pbnbv;
using bus::check_message;
using bus::FieldKind;
using bus::MessageCheck;
using bus::MessageSchema;

namespace {

// A length in an encoding: an array count member or a string's length prefix.
struct LengthField {
  std::string name;    // "arm_status_t.num_joints", "arm_status_t.scan_id"
  std::size_t offset;  // of its first byte
  int width;           // bytes
  bool is_string;
};

void put_int(std::vector<uint8_t>* out, int64_t v, int width) {
  for (int b = width - 1; b >= 0; --b) out->push_back(static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * b)));
}

void set_int(std::vector<uint8_t>* bytes, std::size_t offset, int64_t v, int width) {
  for (int b = 0; b < width; ++b) (*bytes)[offset + b] = static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * (width - 1 - b)));
}

int width_of(FieldKind k) {
  switch (k) {
    case FieldKind::kInt8:
    case FieldKind::kBoolean:
    case FieldKind::kByte: return 1;
    case FieldKind::kInt16: return 2;
    case FieldKind::kInt32:
    case FieldKind::kFloat: return 4;
    default: return 8;
  }
}

// A small valid encoding of struct `index` built from its schema alone: every array length 2,
// every string "ab", every other number 1; the lengths' places recorded.
void encode_sample(int index, const std::string& path, std::vector<uint8_t>* out, std::vector<LengthField>* lengths) {
  const MessageSchema& s = bus::message_schemas()[static_cast<std::size_t>(index)];
  std::vector<bool> is_count(s.fields.size(), false);
  for (const auto& f : s.fields) {
    for (const auto& d : f.dims) {
      if (d.count_field >= 0) is_count[static_cast<std::size_t>(d.count_field)] = true;
    }
  }
  for (std::size_t k = 0; k < s.fields.size(); ++k) {
    const auto& f = s.fields[k];
    const std::string name = path + "." + std::string(f.name);
    int64_t count = 1;
    for (const auto& d : f.dims) count *= d.count_field >= 0 ? 2 : d.fixed;
    for (int64_t e = 0; e < count; ++e) {
      if (f.kind == FieldKind::kString) {
        lengths->push_back({name, out->size(), 4, true});
        put_int(out, 3, 4);
        out->insert(out->end(), {'a', 'b', 0});
      } else if (f.kind == FieldKind::kStruct) {
        encode_sample(f.nested, name, out, lengths);
      } else if (is_count[k]) {
        lengths->push_back({name, out->size(), width_of(f.kind), false});
        put_int(out, 2, width_of(f.kind));
      } else if (f.kind == FieldKind::kFloat) {
        put_int(out, 0x3f000000, 4);  // 0.5f
      } else if (f.kind == FieldKind::kDouble) {
        put_int(out, 0x3fe0000000000000, 8);  // 0.5
      } else {
        put_int(out, 1, width_of(f.kind));
      }
    }
  }
}

template <class T>
std::vector<uint8_t> sample(std::vector<LengthField>* lengths = nullptr) {
  std::vector<LengthField> ignored;
  std::vector<uint8_t> out;
  put_int(&out, T::getHash(), 8);
  const MessageSchema* s = bus::find_schema(T::getTypeName());
  EXPECT_NE(s, nullptr) << T::getTypeName();
  encode_sample(static_cast<int>(s - bus::message_schemas().data()), T::getTypeName(), &out, lengths ? lengths : &ignored);
  return out;
}

template <class T>
MessageCheck check(const std::vector<uint8_t>& bytes, std::size_t size, const bus::DecodeLimits& limits = {}) {
  return check_message(bytes.data(), static_cast<int64_t>(size), T::getTypeName(), T::getHash(), "scan_id", limits);
}

template <class T>
class EveryMessageType : public ::testing::Test {};

using ContractTypes =
    ::testing::Types<arm_command_t, arm_status_t, capture_request_t, depth_frame_t, depth_trigger_t, ellipsoid_set_t,
                     ellipsoid_t, heartbeat_t, mesh_request_t, mesh_result_t, move_request_t, move_result_t,
                     plan_request_t, point_cloud_t, pose_t,
                     registered_cloud_t, scan_status_t, stop_request_t, turntable_command_t, turntable_status_t,
                     view_plan_t, voxel_set_t>;
TYPED_TEST_SUITE(EveryMessageType, ContractTypes);

TEST(MessageSchemas, HoldEveryTypeOfTheContractOnce) {
  // The 22 .lcm files of lcmtypes/: a new one needs its place in ContractTypes above.
  EXPECT_EQ(bus::message_schemas().size(), 22u);
  const MessageSchema* s = bus::find_schema("depth_frame_t");
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->fields.size(), 32u);  // constants are not encoded, not listed
  EXPECT_EQ(s->fields[19].name, "depth");
  EXPECT_EQ(s->fields[19].kind, FieldKind::kByte);
  ASSERT_EQ(s->fields[19].dims.size(), 1u);
  EXPECT_EQ(s->fields[static_cast<std::size_t>(s->fields[19].dims[0].count_field)].name, "num_bytes");
  EXPECT_EQ(s->fields.back().name, "colour");
  EXPECT_EQ(s->fields[static_cast<std::size_t>(s->fields.back().dims[0].count_field)].name, "colour_num_bytes");
  const MessageSchema* cloud = bus::find_schema("point_cloud_t");
  ASSERT_NE(cloud, nullptr);
  ASSERT_EQ(cloud->fields.back().dims.size(), 2u);  // colours[num_colours][3]
  EXPECT_EQ(cloud->fields.back().name, "colours");
  EXPECT_EQ(cloud->fields.back().dims[1].fixed, 3);
  EXPECT_EQ(bus::find_schema("pbnbv_t"), nullptr);
}

TYPED_TEST(EveryMessageType, AValidMessagePassesAndDecodesToTheSameBytes) {
  using T = TypeParam;
  const std::vector<uint8_t> bytes = sample<T>();
  const MessageCheck c = check<T>(bytes, bytes.size());
  ASSERT_TRUE(c.ok) << c.reason;
  T msg;
  ASSERT_EQ(msg.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  std::vector<uint8_t> again(static_cast<std::size_t>(msg.getEncodedSize()));
  ASSERT_EQ(msg.encode(again.data(), 0, static_cast<int>(again.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(again, bytes);
  if constexpr (bus::HasScanId<T>::value && !std::is_same_v<T, heartbeat_t>) {
    EXPECT_TRUE(c.has_scope);
    EXPECT_EQ(c.scope, "ab");  // the sample's every string
  }
  T via;
  std::string why;
  EXPECT_TRUE(bus::decode_checked("TEST", bytes.data(), static_cast<int64_t>(bytes.size()), &via, &why)) << why;
  // One byte more is not this message.
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(check<T>(longer, longer.size()).ok);
}

// Every field zero, so every array empty: passes. (The guard once refused an empty array whose
// other dimensions did not fit in the bytes left, points_m[0][3] at the end of a CLOUD, and with it
// every failed capture's answer: the scan failed waiting for it.)
TYPED_TEST(EveryMessageType, AMessageWithEveryArrayEmptyPasses) {
  using T = TypeParam;
  const T zero{};
  std::vector<uint8_t> bytes(static_cast<std::size_t>(zero.getEncodedSize()));
  ASSERT_EQ(zero.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  const MessageCheck c = check<T>(bytes, bytes.size());
  EXPECT_TRUE(c.ok) << T::getTypeName() << ": " << c.reason;
}

TYPED_TEST(EveryMessageType, EveryPrefixIsRefusedWithoutAllocatingFromItsCounts) {
  using T = TypeParam;
  const std::vector<uint8_t> bytes = sample<T>();
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    allocated_bytes = 0;
    largest_allocation = 0;
    counting = true;
    MessageCheck c;
    EXPECT_NO_THROW(c = check<T>(bytes, n));
    counting = false;
    EXPECT_FALSE(c.ok) << T::getTypeName() << " cut to " << n << " of " << bytes.size() << " bytes";
    EXPECT_FALSE(c.reason.empty());
    // Only the reason's text: a few hundred bytes, whatever the counts say.
    EXPECT_LE(largest_allocation.load(), 512u) << c.reason;
    EXPECT_LE(allocated_bytes.load(), 4096u) << c.reason;
  }
}

TYPED_TEST(EveryMessageType, EveryLengthBeyondTheBytesThatRemainIsRefusedNamingItsField) {
  using T = TypeParam;
  std::vector<LengthField> lengths;
  const std::vector<uint8_t> bytes = sample<T>(&lengths);
  for (const LengthField& f : lengths) {
    const int64_t remain = static_cast<int64_t>(bytes.size() - f.offset) - f.width;
    const int64_t top = f.width == 1 ? 127 : f.width == 2 ? 32767 : 2147483647;
    for (const int64_t claim : {top, remain + 1}) {
      if (claim > top) continue;  // an int8 count cannot say more than 127
      std::vector<uint8_t> bad = bytes;
      set_int(&bad, f.offset, claim, f.width);
      const MessageCheck c = check<T>(bad, bad.size());
      ASSERT_FALSE(c.ok) << f.name << " = " << claim;
      const std::string member = f.name.substr(f.name.rfind('.') + 1);
      if (f.is_string) {
        // "arm_status_t.scan_id claims 2147483647 bytes, 171 remain"
        EXPECT_NE(c.reason.find(f.name + " claims " + std::to_string(claim) + " bytes"), std::string::npos)
            << c.reason;
      } else {
        // "arm_status_t.joint_names claims at least 2147483647 bytes (num_joints = 2147483647), 167 remain"
        EXPECT_NE(c.reason.find("(" + member + " = " + std::to_string(claim) + ")"), std::string::npos) << c.reason;
      }
      EXPECT_NE(c.reason.find(" remain"), std::string::npos) << c.reason;
    }
    // A negative length is no length.
    std::vector<uint8_t> bad = bytes;
    set_int(&bad, f.offset, -1, f.width);
    EXPECT_FALSE(check<T>(bad, bad.size()).ok) << f.name << " = -1";
  }
}

TYPED_TEST(EveryMessageType, RandomBodiesNeverCrashAndWhatPassesDecodes) {
  using T = TypeParam;
  const std::vector<uint8_t> valid = sample<T>();
  std::mt19937 rng(23);
  int passed = 0, refused = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    std::vector<uint8_t> body;
    if (trial % 4 == 0) {  // noise after the right hash
      body.assign(valid.begin(), valid.begin() + 8);
      const int n = static_cast<int>(rng() % 256);
      for (int i = 0; i < n; ++i) body.push_back(static_cast<uint8_t>(rng()));
    } else {  // the valid message with a few bytes changed, maybe cut or lengthened
      body = valid;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int i = 0; i < flips; ++i) {
        body[8 + rng() % (body.size() - 8)] = static_cast<uint8_t>(rng() % 3 == 0 ? 0xff : rng());
      }
      if (rng() % 4 == 0) body.resize(8 + rng() % (body.size() - 7));
      if (rng() % 8 == 0) body.push_back(static_cast<uint8_t>(rng()));
    }
    MessageCheck c;
    ASSERT_NO_THROW(c = check<T>(body, body.size()));
    if (!c.ok) {
      ++refused;
      continue;
    }
    ++passed;
    // Whatever the guard passes, lcm-gen's decoder reads exactly, allocating only what is there.
    T msg;
    ASSERT_EQ(msg.decode(body.data(), 0, static_cast<int>(body.size())), static_cast<int>(body.size()));
    EXPECT_EQ(msg.getEncodedSize(), static_cast<int>(body.size()));
  }
  EXPECT_GT(refused, 0);
  EXPECT_GT(passed, 0) << "no changed byte left a valid " << T::getTypeName();  // e.g. a changed number
}

TEST(MessageGuard, AnotherTypesMessageIsRefusedByItsHash) {
  const std::vector<uint8_t> bytes = sample<arm_command_t>();
  const MessageCheck c = check<arm_status_t>(bytes, bytes.size());
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.reason.find("is not arm_status_t's"), std::string::npos) << c.reason;
}

TEST(MessageGuard, AMessageLargerThanItsTypesLimitIsRefused) {
  heartbeat_t h{};
  h.service = "camera";
  h.last_error.assign(70000, 'x');  // a heartbeat is at most 64 kB
  std::vector<uint8_t> bytes(static_cast<std::size_t>(h.getEncodedSize()));
  h.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const MessageCheck c = check<heartbeat_t>(bytes, bytes.size());
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.reason.find("a heartbeat_t of " + std::to_string(bytes.size()) + " bytes exceeds the largest allowed, 65536"),
            std::string::npos)
      << c.reason;
}

depth_frame_t small_frame(int width, int height, const std::string& scan_id) {
  depth_frame_t f{};
  f.camera_id = "pbnbv-twin";
  f.scan_id = scan_id;
  f.width = width;
  f.height = height;
  f.fx = f.fy = 100;
  f.cx = width / 2.0;
  f.cy = height / 2.0;
  f.depth_min_m = 0.1;
  f.depth_max_m = 3;
  f.depth_unit_m = 1e-4;
  f.encoding = depth_frame_t::kEncodingRaw;
  f.depth.assign(static_cast<std::size_t>(width) * height * 2, 0);
  f.num_bytes = static_cast<int32_t>(f.depth.size());
  return f;
}

template <class T>
std::vector<uint8_t> encoded(const T& m) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

TEST(MessageGuard, AFrameIsHeldToTheLargestImage) {
  bus::DecodeLimits limits;
  limits.max_frame_pixels = 100;  // a 10 x 10 camera
  // 20 x 20: its 800 bytes are more than 100 pixels allow.
  std::vector<uint8_t> bytes = encoded(small_frame(20, 20, "s"));
  MessageCheck c = check<depth_frame_t>(bytes, bytes.size(), limits);
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.reason.find("depth_frame_t.depth claims 800 bytes, the contract allows at most"), std::string::npos)
      << c.reason;
  // 5000 x 5000 declared over 8 bytes of image (compressed, say): 25 M pixels, over 16.7 M.
  depth_frame_t f = small_frame(2, 2, "s");
  f.width = f.height = 5000;
  bytes = encoded(f);
  c = check<depth_frame_t>(bytes, bytes.size());
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.reason.find("depth_frame_t is 5000 x 5000 = 25000000 pixels, the contract allows at most 16777216"),
            std::string::npos)
      << c.reason;
  // The twin's 1280 x 720 passes.
  bytes = encoded(small_frame(1280, 720, "s"));
  EXPECT_TRUE(check<depth_frame_t>(bytes, bytes.size()).ok);
  // Its colour image is held to the same: 5000 x 5000 declared over a few bytes of JPEG.
  f = small_frame(2, 2, "s");
  f.colour_width = f.colour_height = 5000;
  f.colour_encoding = depth_frame_t::kColourJpeg;
  f.colour = {0xFF, 0xD8, 0xFF, 0xD9};
  f.colour_num_bytes = 4;
  bytes = encoded(f);
  c = check<depth_frame_t>(bytes, bytes.size());
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.reason.find("depth_frame_t's colour image is 5000 x 5000 = 25000000 pixels, the contract allows at most "
                          "16777216"),
            std::string::npos)
      << c.reason;
  // And its bytes: 20 x 20 x 3 + 64 kB is the most a 100-pixel camera's colour image may take.
  f = small_frame(2, 2, "s");
  f.colour.assign(300 + 64 * 1024 + 1, 0);
  f.colour_num_bytes = static_cast<int32_t>(f.colour.size());
  bytes = encoded(f);
  c = check<depth_frame_t>(bytes, bytes.size(), limits);
  EXPECT_FALSE(c.ok);
  EXPECT_NE(c.reason.find("depth_frame_t.colour claims 65837 bytes"), std::string::npos) << c.reason;
}

TEST(MessageGuard, TheScanIdIsReadWithoutDecoding) {
  const std::vector<uint8_t> bytes = encoded(small_frame(2, 2, "box-0000000000000002"));
  const MessageCheck c = check<depth_frame_t>(bytes, bytes.size());
  ASSERT_TRUE(c.ok) << c.reason;
  EXPECT_TRUE(c.has_scope);
  EXPECT_EQ(c.scope, "box-0000000000000002");
  heartbeat_t h{};
  h.service = "camera";
  h.scan_id = "last-one";
  h.serves_scan = "bunny-0000000000000001";
  const std::vector<uint8_t> hb = encoded(h);
  const MessageCheck hc =
      check_message(hb.data(), static_cast<int64_t>(hb.size()), "heartbeat_t", heartbeat_t::getHash(), "serves_scan");
  ASSERT_TRUE(hc.ok) << hc.reason;
  EXPECT_EQ(hc.scope, "bunny-0000000000000001");
}

// VmRSS or VmHWM of this process, kB.
int64_t status_kb(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) == 0) return std::stoll(line.substr(key.size() + 1));
  }
  return -1;
}

// The review's attack: ~100-byte DEPTH_FRAMEs whose num_bytes claims 2 GB, sent 60 times to a
// process subscribed to DEPTH_FRAME (over LCM's in-process transport: the real Bus and dispatch).
TEST(MessageGuard, HundredByteFramesClaimingTwoGigabytesAreRefusedOnTheBus) {
  setenv("LCM_DEFAULT_URL", "memq://", 1);
  bus::Bus b("guard-test");
  int handled = 0;
  b.subscribe<depth_frame_t>(channels::kDepthFrame, [&](const depth_frame_t&) { ++handled; });
  depth_frame_t f = small_frame(1, 1, "");
  f.depth.clear();
  f.num_bytes = 0;
  std::vector<uint8_t> bytes = encoded(f);
  // Cut after num_bytes: no image and none of the colour fields after it (an empty colour image's
  // 149 bytes: size 8, intrinsics 32, lens 40, pose 56, utime 8, encoding 1, num_bytes 4).
  bytes.resize(bytes.size() - 149);
  set_int(&bytes, bytes.size() - 4, 2147483647, 4);
  ASSERT_LT(bytes.size(), 180u);  // 163: the header alone (with the lens's 5 doubles)
  const int64_t rss_before = status_kb("VmRSS"), peak_before = status_kb("VmHWM");
  for (int i = 0; i < 60; ++i) {
    b.raw().publish(channels::kDepthFrame, bytes.data(), static_cast<unsigned>(bytes.size()));
    b.spin_once(0);
  }
  for (int i = 0; i < 20 && b.rejected() < 60; ++i) b.spin_once(10);
  const int64_t rss_after = status_kb("VmRSS"), peak_after = status_kb("VmHWM");
  std::printf("VmRSS %lld -> %lld kB, VmHWM %lld -> %lld kB\n", static_cast<long long>(rss_before),
              static_cast<long long>(rss_after), static_cast<long long>(peak_before), static_cast<long long>(peak_after));
  EXPECT_EQ(b.rejected(), 60);
  EXPECT_EQ(handled, 0);
  EXPECT_LT(peak_after - peak_before, 4096);  // kB
  EXPECT_LT(rss_after - rss_before, 4096);
  // The reason, as a log reader or decode_checked says it.
  depth_frame_t m;
  std::string why;
  EXPECT_FALSE(bus::decode_checked("DEPTH_FRAME", bytes.data(), static_cast<int64_t>(bytes.size()), &m, &why));
  EXPECT_EQ(why, "DEPTH_FRAME: depth_frame_t.depth claims 2147483647 bytes (num_bytes = 2147483647), 0 remain");
}

TEST(MessageGuard, AnotherScansMessageIsIgnoredBeforeItIsDecoded) {
  setenv("LCM_DEFAULT_URL", "memq://", 1);
  bus::Bus b("guard-test");
  b.serve_scan("bunny-0000000000000001");
  int handled = 0;
  b.subscribe<depth_frame_t>(channels::kDepthFrame, [&](const depth_frame_t&) { ++handled; });
  const std::vector<uint8_t> other = encoded(small_frame(2, 2, "box-0000000000000002"));
  const std::vector<uint8_t> mine = encoded(small_frame(2, 2, "bunny-0000000000000001"));
  b.raw().publish(channels::kDepthFrame, other.data(), static_cast<unsigned>(other.size()));
  b.raw().publish(channels::kDepthFrame, mine.data(), static_cast<unsigned>(mine.size()));
  for (int i = 0; i < 20 && b.ignored() + b.handled() < 2; ++i) b.spin_once(10);
  EXPECT_EQ(b.ignored(), 1);
  EXPECT_EQ(handled, 1);
  EXPECT_EQ(b.rejected(), 0);
}

// A zlib stream of `n` zero bytes, compressed a chunk at a time (the bomb is built without holding
// what it inflates to).
std::vector<uint8_t> zeros_compressed(std::size_t n) {
  z_stream z{};
  deflateInit(&z, 9);
  std::vector<uint8_t> chunk(1 << 20, 0), out;
  std::vector<uint8_t> buf(1 << 16);
  std::size_t left = n;
  int flush = Z_NO_FLUSH;
  do {
    const std::size_t take = std::min(left, chunk.size());
    left -= take;
    flush = left == 0 ? Z_FINISH : Z_NO_FLUSH;
    z.next_in = chunk.data();
    z.avail_in = static_cast<uInt>(take);
    do {
      z.next_out = buf.data();
      z.avail_out = static_cast<uInt>(buf.size());
      deflate(&z, flush);
      out.insert(out.end(), buf.data(), buf.data() + (buf.size() - z.avail_out));
    } while (z.avail_out == 0);
  } while (flush != Z_FINISH);
  deflateEnd(&z);
  return out;
}

TEST(DepthCodec, AZlibBombIsRefusedNamingTheFrameWithoutInflatingIt) {
  // The review's bomb: about 130 kB inflating to an 8192 x 8192 image (128 MB).
  depth_frame_t f = small_frame(1, 1, "");
  f.seq = 7;
  f.width = f.height = 8192;
  f.cx = f.cy = 4096;
  f.encoding = depth_frame_t::kEncodingZlib;
  f.depth = zeros_compressed(std::size_t{8192} * 8192 * 2);
  f.num_bytes = static_cast<int32_t>(f.depth.size());
  EXPECT_LT(f.depth.size(), 200000u);
  const int64_t peak_before = status_kb("VmHWM");
  for (int i = 0; i < 4; ++i) {
    try {
      bus::decode_frame(f);
      ADD_FAILURE() << "the bomb decoded";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("DEPTH_FRAME 7"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("8192 x 8192"), std::string::npos) << e.what();
    }
  }
  EXPECT_LT(status_kb("VmHWM") - peak_before, 4096);  // kB
  // The guard refuses the same frame on the bus before it is decoded.
  const std::vector<uint8_t> bytes = encoded(f);
  EXPECT_FALSE(check<depth_frame_t>(bytes, bytes.size()).ok);
}

TEST(DepthCodec, InflationIsBoundedByTheDeclaredAndTheAllowedSize) {
  const std::vector<uint8_t> packed = zeros_compressed(10000);
  EXPECT_EQ(bus::inflate_bytes(packed, 10000, 20000, "frame 1").size(), 10000u);
  // Declared over the allowed size: refused before anything is allocated.
  try {
    bus::inflate_bytes(packed, 30000, 20000, "DEPTH_FRAME 2 depth (zlib)");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "DEPTH_FRAME 2 depth (zlib) declares 30000 bytes, more than the 20000 allowed");
  }
  // 100 bytes cannot inflate to 1 MB (1032 : 1 at most).
  const std::vector<uint8_t> hundred(packed.begin(), packed.begin() + std::min<std::size_t>(100, packed.size()));
  try {
    bus::inflate_bytes(hundred, 1 << 20, 1 << 24, "DEPTH_FRAME 3 depth (zlib)");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("which " + std::to_string(hundred.size()) + " compressed bytes cannot inflate to"),
              std::string::npos)
        << e.what();
  }
  // Inflating to more than declared: refused, the buffer the declared size.
  EXPECT_THROW(bus::inflate_bytes(packed, 5000, 20000, "DEPTH_FRAME 4 depth (zlib)"), std::invalid_argument);
}

}  // namespace
