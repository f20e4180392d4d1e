#include "bus/message_guard.hpp"

#include <zlib.h>

#include <array>
#include <cstdio>
#include <stdexcept>

#include "bus/message_schema.hpp"

namespace pbnbv::bus {

namespace {

constexpr int64_t kKiB = 1024;
constexpr int64_t kMiB = 1024 * kKiB;
// A struct's integer members are kept while it is walked (array lengths refer back to them): on
// the stack, so the walk allocates nothing. The contract's largest struct has 45 members.
constexpr std::size_t kMaxMembers = 96;
// Nested structs inside nested structs: the contract goes two deep.
constexpr int kMaxDepth = 8;

int64_t primitive_size(FieldKind k) {
  switch (k) {
    case FieldKind::kInt8:
    case FieldKind::kBoolean:
    case FieldKind::kByte: return 1;
    case FieldKind::kInt16: return 2;
    case FieldKind::kInt32:
    case FieldKind::kFloat: return 4;
    case FieldKind::kInt64:
    case FieldKind::kDouble: return 8;
    case FieldKind::kString:
    case FieldKind::kStruct: return 0;
  }
  return 0;
}

// What the walk needs of each struct beyond its schema, computed once: the fewest bytes one takes
// (every array empty, every string "") and, for a struct without strings or member-given lengths,
// its one size (an array of them is stepped over without visiting each).
struct StructSizes {
  std::vector<int64_t> min_bytes;
  std::vector<int64_t> fixed_bytes;  // -1: varies
};

StructSizes compute_sizes() {
  const std::vector<MessageSchema>& all = message_schemas();
  StructSizes s{std::vector<int64_t>(all.size(), -2), std::vector<int64_t>(all.size(), -1)};
  // Nested structs come in any order in the table: fill in rounds until every struct is known
  // (the generator refuses a struct that contains itself).
  for (std::size_t round = 0; round <= all.size(); ++round) {
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (s.min_bytes[i] != -2) continue;
      if (all[i].fields.size() > kMaxMembers) {
        throw std::logic_error(std::string(all[i].name) + " has more members than the message guard keeps");
      }
      int64_t min = 0;
      bool fixed = true, known = true;
      for (const FieldSchema& f : all[i].fields) {
        int64_t fixed_count = 1;
        for (const ArrayDim& d : f.dims) {
          if (d.count_field >= 0) fixed = false, fixed_count = 0;
          else fixed_count *= d.fixed;
        }
        int64_t element_min = primitive_size(f.kind), element_fixed = element_min;
        if (f.kind == FieldKind::kString) element_min = 5, fixed = false;  // int32 length + NUL
        if (f.kind == FieldKind::kStruct) {
          if (s.min_bytes[f.nested] == -2) known = false;
          element_min = s.min_bytes[f.nested];
          element_fixed = s.fixed_bytes[f.nested];
          if (element_fixed < 0) fixed = false;
        }
        min += fixed_count * element_min;
      }
      if (!known) continue;
      s.min_bytes[i] = min;
      s.fixed_bytes[i] = fixed ? min : -1;
    }
  }
  return s;
}

const StructSizes& struct_sizes() {
  static const StructSizes sizes = compute_sizes();
  return sizes;
}

// Walks one encoding. Reads only inside [0, size); on the first fault it stops with `error` set.
class Walker {
 public:
  Walker(const uint8_t* data, int64_t size, const DecodeLimits& limits, std::string_view scope_field)
      : data_(data), size_(size), limits_(limits), scope_field_(scope_field) {}

  bool walk_struct(int index, const std::string& path, int depth) {
    const MessageSchema& s = message_schemas()[static_cast<std::size_t>(index)];
    if (depth > kMaxDepth) return fail(path + " nests deeper than " + std::to_string(kMaxDepth) + " structs");
    std::array<int64_t, kMaxMembers> values{};
    for (std::size_t k = 0; k < s.fields.size(); ++k) {
      const FieldSchema& f = s.fields[k];
      // How many elements: the product of the dimensions, each checked against the bytes that
      // remain before multiplying (every element takes at least one byte).
      int64_t count = 1;
      std::string_view by;  // the member giving a length, for the reason
      int64_t by_value = 0;
      for (const ArrayDim& d : f.dims) {
        const int64_t n = d.count_field >= 0 ? values[static_cast<std::size_t>(d.count_field)] : d.fixed;
        if (d.count_field >= 0) by = s.fields[static_cast<std::size_t>(d.count_field)].name, by_value = n;
        if (n < 0) {
          return fail(path + "." + std::string(f.name) + " has a negative length (" + std::string(by) + " = " +
                      std::to_string(n) + ")");
        }
        // (An empty array claims nothing, whatever its other dimensions: points_m[0][3].)
        if (count > 0 && n > remaining()) return fail_claim(path, f, by, by_value, n);
        count *= n;
        if (count > remaining()) return fail_claim(path, f, by, by_value, count);
      }
      const int64_t most = limits_.max_elements(s.name, f.name);
      if (most >= 0 && count > most) {
        return fail(path + "." + std::string(f.name) + " claims " + std::to_string(count) + " " + unit(f) +
                    ", the contract allows at most " + std::to_string(most));
      }
      if (f.kind == FieldKind::kString) {
        for (int64_t e = 0; e < count; ++e) {
          const int64_t length = read_int(4);
          if (length == kShort) return fail_short(path, f, 4);
          if (length < 1) {
            return fail(path + "." + std::string(f.name) + " has length " + std::to_string(length) +
                        " (at least 1: the terminating NUL is counted)");
          }
          if (length > remaining()) {
            return fail(path + "." + std::string(f.name) + " claims " + std::to_string(length) + " bytes, " +
                        std::to_string(remaining()) + " remain");
          }
          if (depth == 0 && f.dims.empty() && f.name == scope_field_) {
            has_scope_ = true;
            scope_ = std::string_view(reinterpret_cast<const char*>(data_ + pos_), static_cast<std::size_t>(length - 1));
          }
          pos_ += length;
        }
      } else if (f.kind == FieldKind::kStruct) {
        const StructSizes& sizes = struct_sizes();
        const int64_t fixed = sizes.fixed_bytes[static_cast<std::size_t>(f.nested)];
        const int64_t min = sizes.min_bytes[static_cast<std::size_t>(f.nested)];
        if (min > 0 && count > remaining() / min) return fail_claim(path, f, by, by_value, count * min);
        if (fixed >= 0) {
          pos_ += count * fixed;
        } else {
          for (int64_t e = 0; e < count; ++e) {
            if (!walk_struct(f.nested, path + "." + std::string(f.name), depth + 1)) return false;
          }
        }
      } else {
        const int64_t bytes = count * primitive_size(f.kind);
        if (bytes > remaining()) return fail_claim(path, f, by, by_value, bytes);
        if (f.dims.empty() && f.kind != FieldKind::kFloat && f.kind != FieldKind::kDouble) {
          values[k] = read_int(static_cast<int>(bytes));
        } else {
          pos_ += bytes;
        }
      }
    }
    if (depth == 0) top_values_ = values;
    return true;
  }

  int64_t position() const { return pos_; }
  int64_t remaining() const { return size_ - pos_; }
  const std::string& error() const { return error_; }
  bool has_scope() const { return has_scope_; }
  std::string_view scope() const { return scope_; }
  int64_t top_value(std::size_t k) const { return top_values_[k]; }

 private:
  static constexpr int64_t kShort = INT64_MIN;

  // A big-endian signed integer of `bytes` bytes, or kShort when fewer remain.
  int64_t read_int(int bytes) {
    if (remaining() < bytes) return kShort;
    uint64_t v = 0;
    for (int b = 0; b < bytes; ++b) v = (v << 8) | data_[pos_ + b];
    pos_ += bytes;
    switch (bytes) {
      case 1: return static_cast<int8_t>(v);
      case 2: return static_cast<int16_t>(v);
      case 4: return static_cast<int32_t>(v);
      default: return static_cast<int64_t>(v);
    }
  }

  static std::string unit(const FieldSchema& f) {
    return f.kind == FieldKind::kByte ? "bytes" : f.kind == FieldKind::kString ? "strings" : "elements";
  }

  bool fail(std::string why) {
    error_ = std::move(why);
    return false;
  }
  bool fail_short(const std::string& path, const FieldSchema& f, int64_t need) {
    return fail(path + "." + std::string(f.name) + " needs " + std::to_string(need) + " bytes, " +
                std::to_string(remaining()) + " remain (the message is cut short)");
  }
  // "depth_frame_t.depth claims 2147483647 bytes (num_bytes = 2147483647), 84 remain"
  bool fail_claim(const std::string& path, const FieldSchema& f, std::string_view by, int64_t length,
                  int64_t bytes_needed) {
    std::string s = path + "." + std::string(f.name) + " claims ";
    if (f.kind == FieldKind::kByte) s += std::to_string(bytes_needed) + " bytes";
    else s += "at least " + std::to_string(bytes_needed) + " bytes";
    if (!by.empty()) s += " (" + std::string(by) + " = " + std::to_string(length) + ")";
    return fail(s + ", " + std::to_string(remaining()) + " remain");
  }

  const uint8_t* data_;
  int64_t size_;
  int64_t pos_ = 0;
  const DecodeLimits& limits_;
  std::string_view scope_field_;
  std::string error_;
  bool has_scope_ = false;
  std::string_view scope_;
  std::array<int64_t, kMaxMembers> top_values_{};
};

int find_index(std::string_view type_name) {
  const std::vector<MessageSchema>& all = message_schemas();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].name == type_name) return static_cast<int>(i);
  }
  return -1;
}

int member_index(const MessageSchema& s, std::string_view name) {
  for (std::size_t k = 0; k < s.fields.size(); ++k) {
    if (s.fields[k].name == name) return static_cast<int>(k);
  }
  return -1;
}

std::string hex(int64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// The bytes of a depth image of `pixels` pixels, raw or compressed at worst (zlib may grow
// incompressible data slightly).
int64_t frame_bytes(int64_t pixels) {
  return static_cast<int64_t>(compressBound(static_cast<uLong>(2 * pixels)));
}

// The bytes of a frame's colour image of `pixels` pixels: raw R G B (a JPEG of it is smaller but
// for its headers on a tiny image; 64 kB covers those).
int64_t colour_bytes(int64_t pixels) { return 3 * pixels + 64 * kKiB; }

}  // namespace

const MessageSchema* find_schema(std::string_view type_name) {
  const int i = find_index(type_name);
  return i < 0 ? nullptr : &message_schemas()[static_cast<std::size_t>(i)];
}

int64_t DecodeLimits::max_message_bytes(std::string_view type_name) const {
  // Room for a message's scalars and strings around its arrays.
  constexpr int64_t kSmall = 64 * kKiB;
  if (type_name == "depth_frame_t") return frame_bytes(max_frame_pixels) + colour_bytes(max_frame_pixels) + kSmall;
  // A cloud has at most one point (12 bytes), one normal (12 bytes) and one colour (3 bytes) per
  // pixel of its frame.
  if (type_name == "point_cloud_t" || type_name == "registered_cloud_t") return 27 * max_frame_pixels + kSmall;
  // Every cell of B, a byte each, plus its occupied and frontier centres: a B of 400^3 cells.
  if (type_name == "voxel_set_t") return 256 * kMiB;
  // Poses of the views taken and excluded (up to 1000 views each), candidates' alternatives and
  // sectors, ellipsoids: well under 4 MB for any scan the settings allow.
  if (type_name == "plan_request_t" || type_name == "view_plan_t" || type_name == "ellipsoid_set_t") return 4 * kMiB;
  return kSmall;  // commands, statuses, requests, results, heartbeats
}

int64_t DecodeLimits::max_elements(std::string_view type_name, std::string_view field) const {
  if (type_name == "depth_frame_t" && field == "depth") return frame_bytes(max_frame_pixels);
  if (type_name == "depth_frame_t" && field == "colour") return colour_bytes(max_frame_pixels);
  if (type_name == "point_cloud_t" && (field == "points_m" || field == "normals" || field == "colours")) {
    return 3 * max_frame_pixels;
  }
  return -1;
}

MessageCheck check_message(const void* data, int64_t size, std::string_view type_name, int64_t expected_hash,
                           std::string_view scope_field, const DecodeLimits& limits) {
  MessageCheck c;
  const std::string type(type_name);
  const int index = find_index(type_name);
  if (index < 0) {
    c.reason = type + " is not a type of the contract (lcmtypes/)";
    return c;
  }
  const int64_t most = limits.max_message_bytes(type_name);
  if (size > most) {
    c.reason = "a " + type + " of " + std::to_string(size) + " bytes exceeds the largest allowed, " +
               std::to_string(most) + " bytes";
    return c;
  }
  if (size < 8) {
    c.reason = std::to_string(size) + " bytes cannot hold a " + type + " (8 bytes of type hash first)";
    return c;
  }
  const auto* bytes = static_cast<const uint8_t*>(data);
  uint64_t hash = 0;
  for (int b = 0; b < 8; ++b) hash = (hash << 8) | bytes[b];
  if (static_cast<int64_t>(hash) != expected_hash) {
    c.reason = "type hash " + hex(static_cast<int64_t>(hash)) + " is not " + type + "'s " + hex(expected_hash) +
               " (another type, or another version of the contract)";
    return c;
  }
  Walker w(bytes + 8, size - 8, limits, scope_field);
  if (!w.walk_struct(index, type, 0)) {
    c.reason = w.error();
    return c;
  }
  if (w.remaining() != 0) {
    c.reason = type + " ends after " + std::to_string(8 + w.position()) + " bytes, " + std::to_string(w.remaining()) +
               " more follow";
    return c;
  }
  // The contract's frame size: the image's declared width x height, which the decoder of the
  // image (decode_frame) inflates to.
  if (type_name == "depth_frame_t") {
    const MessageSchema& s = message_schemas()[static_cast<std::size_t>(index)];
    // "" when the image the members `w_name` x `h_name` declare is within the contract's largest.
    const auto too_large = [&](const char* w_name, const char* h_name, const std::string& what) -> std::string {
      const int w_at = member_index(s, w_name), h_at = member_index(s, h_name);
      const int64_t width = w_at < 0 ? 0 : w.top_value(static_cast<std::size_t>(w_at));
      const int64_t height = h_at < 0 ? 0 : w.top_value(static_cast<std::size_t>(h_at));
      if (width <= 0 || height <= 0 || width * height <= limits.max_frame_pixels) return "";
      return what + " is " + std::to_string(width) + " x " + std::to_string(height) + " = " +
             std::to_string(width * height) + " pixels, the contract allows at most " +
             std::to_string(limits.max_frame_pixels);
    };
    c.reason = too_large("width", "height", type);
    if (c.reason.empty()) c.reason = too_large("colour_width", "colour_height", type + "'s colour image");
    if (!c.reason.empty()) return c;
  }
  c.ok = true;
  c.has_scope = w.has_scope();
  c.scope = w.scope();
  return c;
}

}  // namespace pbnbv::bus
