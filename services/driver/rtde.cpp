#include "driver/rtde.hpp"

#include <cmath>
#include <cstring>
#include <sstream>

namespace pbnbv::driver::rtde {

namespace {

// Big-endian writing into a payload.
class Writer {
 public:
  void u8(uint8_t v) { out_.push_back(v); }
  void u16(uint16_t v) { uint(v, 2); }
  void u32(uint32_t v) { uint(v, 4); }
  void u64(uint64_t v) { uint(v, 8); }
  void f64(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    u64(bits);
  }
  void text(const std::string& s) { out_.insert(out_.end(), s.begin(), s.end()); }
  std::vector<uint8_t> take() { return std::move(out_); }

 private:
  void uint(uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  std::vector<uint8_t> out_;
};

// Big-endian reading of a payload; reading past its end is an RtdeError naming the package.
class Reader {
 public:
  explicit Reader(const Package& p) : p_(p) {}
  uint8_t u8() { return static_cast<uint8_t>(uint(1, "uint8")); }
  uint16_t u16() { return static_cast<uint16_t>(uint(2, "uint16")); }
  uint32_t u32() { return static_cast<uint32_t>(uint(4, "uint32")); }
  uint64_t u64() { return uint(8, "uint64"); }
  double f64() {
    const uint64_t bits = uint(8, "double");
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  std::string text(std::size_t n, const char* what) {
    need(n, what);
    std::string s(p_.payload.begin() + static_cast<long>(at_), p_.payload.begin() + static_cast<long>(at_ + n));
    at_ += n;
    return s;
  }
  std::string rest() { return text(left(), "text"); }
  std::size_t left() const { return p_.payload.size() - at_; }
  // The payload must be used up: trailing bytes are an error.
  void done() const {
    if (left() != 0) {
      throw RtdeError(type_label(p_.type) + ": " + std::to_string(left()) + " unexpected bytes after the payload (" +
                      std::to_string(p_.payload.size()) + " bytes)");
    }
  }

 private:
  void need(std::size_t n, const char* what) const {
    if (left() < n) {
      throw RtdeError(type_label(p_.type) + ": payload of " + std::to_string(p_.payload.size()) +
                      " bytes ends before its " + what + " (byte " + std::to_string(at_) + ")");
    }
  }
  uint64_t uint(int bytes, const char* what) {
    need(static_cast<std::size_t>(bytes), what);
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v = (v << 8) | p_.payload[at_++];
    return v;
  }
  const Package& p_;
  std::size_t at_ = 0;
};

void expect_type(const Package& p, uint8_t expected) {
  if (p.type != expected) throw RtdeError("expected " + type_label(expected) + ", got " + type_label(p.type));
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(s);
  while (std::getline(in, part, sep)) parts.push_back(part);
  if (!s.empty() && s.back() == sep) parts.push_back("");
  return parts;
}

std::string joined(const std::vector<std::string>& names, const char* what) {
  if (names.empty()) throw std::invalid_argument(std::string(what) + ": no variable names");
  std::string s;
  for (const std::string& n : names) {
    if (n.empty() || n.find(',') != std::string::npos) {
      throw std::invalid_argument(std::string(what) + ": variable name '" + n + "' is empty or holds a comma");
    }
    s += (s.empty() ? "" : ",") + n;
  }
  return s;
}

// Throws std::invalid_argument unless `v` fits field `i` of type v.type.
void check_value(const Value& v, std::size_t i) {
  const std::string field = "data package field " + std::to_string(i) + " (" + type_name(v.type) + ")";
  if (v.type == Type::kVector3d || v.type == Type::kVector6d) {
    const std::size_t n = v.type == Type::kVector3d ? 3 : 6;
    if (v.vector.size() != n) throw std::invalid_argument(field + ": " + std::to_string(v.vector.size()) + " numbers");
    return;
  }
  if (v.type == Type::kDouble) return;
  const double lo = v.type == Type::kInt32 ? -2147483648.0 : 0.0;
  const double hi = v.type == Type::kBool ? 1 : v.type == Type::kUint8 ? 255 : v.type == Type::kInt32 ? 2147483647.0
                    : v.type == Type::kUint32 ? 4294967295.0 : 9007199254740992.0;
  if (!(v.number == std::floor(v.number) && v.number >= lo && v.number <= hi)) {
    std::ostringstream os;
    os << field << ": " << v.number << " is not an integer in [" << lo << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
}

void write_value(Writer& w, const Value& v) {
  switch (v.type) {
    case Type::kBool:
    case Type::kUint8: w.u8(static_cast<uint8_t>(v.number)); break;
    case Type::kInt32: w.u32(static_cast<uint32_t>(static_cast<int32_t>(v.number))); break;
    case Type::kUint32: w.u32(static_cast<uint32_t>(v.number)); break;
    case Type::kUint64: w.u64(static_cast<uint64_t>(v.number)); break;
    case Type::kDouble: w.f64(v.number); break;
    case Type::kVector3d:
    case Type::kVector6d:
      for (double x : v.vector) w.f64(x);
      break;
  }
}

Value read_value(Reader& r, Type t) {
  Value v;
  v.type = t;
  switch (t) {
    case Type::kBool:
    case Type::kUint8: v.number = r.u8(); break;
    case Type::kInt32: v.number = static_cast<int32_t>(r.u32()); break;
    case Type::kUint32: v.number = r.u32(); break;
    case Type::kUint64: v.number = static_cast<double>(r.u64()); break;
    case Type::kDouble: v.number = r.f64(); break;
    case Type::kVector3d:
    case Type::kVector6d:
      for (std::size_t i = 0; i < (t == Type::kVector3d ? 3u : 6u); ++i) v.vector.push_back(r.f64());
      break;
  }
  return v;
}

}  // namespace

std::string type_label(uint8_t type) {
  const char* name = nullptr;
  switch (type) {
    case kRequestProtocolVersion: name = "request protocol version"; break;
    case kGetUrControlVersion: name = "get URControl version"; break;
    case kTextMessage: name = "text message"; break;
    case kDataPackage: name = "data package"; break;
    case kSetupOutputs: name = "setup outputs"; break;
    case kSetupInputs: name = "setup inputs"; break;
    case kStart: name = "start"; break;
    case kPause: name = "pause"; break;
  }
  if (name) return std::string("'") + static_cast<char>(type) + "' (" + name + ")";
  return "package type " + std::to_string(type) + " (unknown)";
}

std::vector<uint8_t> encode(const Package& package) {
  const std::size_t size = kHeaderSize + package.payload.size();
  if (size > kMaxPackageSize) {
    throw RtdeError(type_label(package.type) + ": " + std::to_string(size) + " bytes exceed the limit of " +
                    std::to_string(kMaxPackageSize));
  }
  std::vector<uint8_t> out{static_cast<uint8_t>(size >> 8), static_cast<uint8_t>(size & 0xff), package.type};
  out.insert(out.end(), package.payload.begin(), package.payload.end());
  return out;
}

void Framer::feed(const uint8_t* data, std::size_t n) { buffer_.insert(buffer_.end(), data, data + n); }

std::optional<Package> Framer::next() {
  if (buffer_.size() < kHeaderSize) return std::nullopt;
  const std::size_t size = (std::size_t{buffer_[0]} << 8) | buffer_[1];
  const uint8_t type = buffer_[2];
  if (size < kHeaderSize || size > kMaxPackageSize) {
    throw RtdeError(type_label(type) + ": size field " + std::to_string(size) + " outside " +
                    std::to_string(kHeaderSize) + ".." + std::to_string(kMaxPackageSize));
  }
  if (buffer_.size() < size) return std::nullopt;
  Package p;
  p.type = type;
  p.payload.assign(buffer_.begin() + kHeaderSize, buffer_.begin() + static_cast<long>(size));
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<long>(size));
  return p;
}

Package decode(const std::vector<uint8_t>& bytes) {
  if (bytes.size() < kHeaderSize) {
    throw RtdeError("package of " + std::to_string(bytes.size()) + " bytes is shorter than its 3-byte header");
  }
  const std::size_t size = (std::size_t{bytes[0]} << 8) | bytes[1];
  if (size != bytes.size()) {
    throw RtdeError(type_label(bytes[2]) + ": size field " + std::to_string(size) + " but " +
                    std::to_string(bytes.size()) + " bytes");
  }
  Framer f;
  f.feed(bytes.data(), bytes.size());
  return *f.next();  // bounds checked there
}

const char* type_name(Type t) {
  switch (t) {
    case Type::kBool: return "BOOL";
    case Type::kUint8: return "UINT8";
    case Type::kInt32: return "INT32";
    case Type::kUint32: return "UINT32";
    case Type::kUint64: return "UINT64";
    case Type::kDouble: return "DOUBLE";
    case Type::kVector3d: return "VECTOR3D";
    case Type::kVector6d: return "VECTOR6D";
  }
  return "?";
}

std::optional<Type> type_of(const std::string& name) {
  for (Type t : {Type::kBool, Type::kUint8, Type::kInt32, Type::kUint32, Type::kUint64, Type::kDouble, Type::kVector3d,
                 Type::kVector6d}) {
    if (name == type_name(t)) return t;
  }
  return std::nullopt;
}

std::size_t size_of(Type t) {
  switch (t) {
    case Type::kBool:
    case Type::kUint8: return 1;
    case Type::kInt32:
    case Type::kUint32: return 4;
    case Type::kUint64:
    case Type::kDouble: return 8;
    case Type::kVector3d: return 24;
    case Type::kVector6d: return 48;
  }
  return 0;
}

Value scalar(Type t, double number) {
  Value v;
  v.type = t;
  v.number = number;
  return v;
}

Value vector6(const std::array<double, 6>& a) {
  Value v;
  v.type = Type::kVector6d;
  v.vector.assign(a.begin(), a.end());
  return v;
}

Package request_protocol_version(uint16_t version) {
  Writer w;
  w.u16(version);
  return {kRequestProtocolVersion, w.take()};
}

Package get_urcontrol_version() { return {kGetUrControlVersion, {}}; }

Package setup_outputs(double frequency_hz, const std::vector<std::string>& names) {
  Writer w;
  w.f64(frequency_hz);
  w.text(joined(names, "setup outputs"));
  return {kSetupOutputs, w.take()};
}

Package setup_inputs(const std::vector<std::string>& names) {
  Writer w;
  w.text(joined(names, "setup inputs"));
  return {kSetupInputs, w.take()};
}

Package start() { return {kStart, {}}; }
Package pause() { return {kPause, {}}; }

Package data_package(const Data& data) {
  Writer w;
  w.u8(data.recipe_id);
  for (std::size_t i = 0; i < data.values.size(); ++i) {
    check_value(data.values[i], i);
    write_value(w, data.values[i]);
  }
  return {kDataPackage, w.take()};
}

bool parse_accepted(const Package& p, uint8_t expected_type) {
  expect_type(p, expected_type);
  Reader r(p);
  const uint8_t accepted = r.u8();
  r.done();
  return accepted != 0;
}

UrControlVersion parse_urcontrol_version(const Package& p) {
  expect_type(p, kGetUrControlVersion);
  Reader r(p);
  UrControlVersion v;
  v.major = r.u32();
  v.minor = r.u32();
  v.bugfix = r.u32();
  v.build = r.u32();
  r.done();
  return v;
}

SetupAnswer parse_setup_answer(const Package& p, uint8_t expected_type) {
  expect_type(p, expected_type);
  Reader r(p);
  SetupAnswer a;
  a.recipe_id = r.u8();
  a.types = split(r.rest(), ',');
  return a;
}

std::vector<Type> recipe_types(const SetupAnswer& answer, const std::vector<std::string>& names,
                               const std::vector<Type>& expected) {
  if (answer.types.size() != names.size()) {
    throw RtdeError("recipe " + std::to_string(answer.recipe_id) + ": " + std::to_string(answer.types.size()) +
                    " types for " + std::to_string(names.size()) + " variables");
  }
  std::vector<Type> types;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& t = answer.types[i];
    if (t == "NOT_FOUND") throw RtdeError("the controller does not know the variable " + names[i] + " (NOT_FOUND)");
    if (t == "IN_USE") {
      throw RtdeError("the variable " + names[i] + " is in use by another RTDE client or program (IN_USE)");
    }
    const std::optional<Type> type = type_of(t);
    if (!type) throw RtdeError("the variable " + names[i] + " has the unknown type '" + t + "'");
    if (!expected.empty() && expected.size() == names.size() && *type != expected[i]) {
      throw RtdeError("the variable " + names[i] + " is " + t + ", expected " + type_name(expected[i]));
    }
    types.push_back(*type);
  }
  return types;
}

TextMessage parse_text_message(const Package& p) {
  expect_type(p, kTextMessage);
  Reader r(p);
  TextMessage m;
  const uint8_t message_size = r.u8();
  m.message = r.text(message_size, "message");
  const uint8_t source_size = r.u8();
  m.source = r.text(source_size, "source");
  m.level = r.u8();
  r.done();
  return m;
}

Package text_message(const TextMessage& m) {
  if (m.message.size() > 255 || m.source.size() > 255) {
    throw std::invalid_argument("text message: message or source over 255 bytes");
  }
  Writer w;
  w.u8(static_cast<uint8_t>(m.message.size()));
  w.text(m.message);
  w.u8(static_cast<uint8_t>(m.source.size()));
  w.text(m.source);
  w.u8(m.level);
  return {kTextMessage, w.take()};
}

Data parse_data_package(const Package& p, uint8_t recipe_id, const std::vector<Type>& recipe) {
  expect_type(p, kDataPackage);
  std::size_t size = 1;
  for (Type t : recipe) size += size_of(t);
  if (p.payload.size() != size) {
    throw RtdeError(type_label(p.type) + ": " + std::to_string(p.payload.size()) + " payload bytes, recipe " +
                    std::to_string(recipe_id) + " makes " + std::to_string(size));
  }
  Reader r(p);
  Data d;
  d.recipe_id = r.u8();
  if (d.recipe_id != recipe_id) {
    throw RtdeError(type_label(p.type) + ": recipe id " + std::to_string(d.recipe_id) + ", expected " +
                    std::to_string(recipe_id));
  }
  for (Type t : recipe) d.values.push_back(read_value(r, t));
  return d;
}

Package accepted_answer(uint8_t type, bool accepted) { return {type, {static_cast<uint8_t>(accepted ? 1 : 0)}}; }

Package urcontrol_version_answer(const UrControlVersion& v) {
  Writer w;
  w.u32(v.major);
  w.u32(v.minor);
  w.u32(v.bugfix);
  w.u32(v.build);
  return {kGetUrControlVersion, w.take()};
}

Package setup_answer(uint8_t type, const SetupAnswer& answer) {
  Writer w;
  w.u8(answer.recipe_id);
  std::string types;
  for (const std::string& t : answer.types) types += (types.empty() ? "" : ",") + t;
  w.text(types);
  return {type, w.take()};
}

uint16_t parse_protocol_version_request(const Package& p) {
  expect_type(p, kRequestProtocolVersion);
  Reader r(p);
  const uint16_t v = r.u16();
  r.done();
  return v;
}

SetupRequest parse_setup_request(const Package& p) {
  if (p.type != kSetupOutputs && p.type != kSetupInputs) {
    throw RtdeError("expected " + type_label(kSetupOutputs) + " or " + type_label(kSetupInputs) + ", got " +
                    type_label(p.type));
  }
  Reader r(p);
  SetupRequest s;
  if (p.type == kSetupOutputs) {
    s.frequency_hz = r.f64();
    if (!(s.frequency_hz > 0 && s.frequency_hz <= 500)) {
      throw RtdeError(type_label(p.type) + ": frequency " + std::to_string(s.frequency_hz) + " Hz outside (0, 500]");
    }
  }
  const std::string names = r.rest();
  if (names.empty()) throw RtdeError(type_label(p.type) + ": no variable names");
  s.names = split(names, ',');
  return s;
}

}  // namespace pbnbv::driver::rtde
