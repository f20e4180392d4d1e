#pragma once
// Universal Robots' RTDE protocol (Real-Time Data Exchange, TCP port 30004, protocol version 2) as
// plain functions on bytes: packages framed, requests and answers encoded and decoded, a data
// package read and written by its recipe. No sockets here: pbnbv-ur-driver
// (services/ur_driver) and the twin's controller (twin/ur_controller.hpp) move the bytes.
//
// A package is uint16 size (big-endian, counting the 3-byte header) + uint8 type + payload; every
// number is big-endian. Every size read from the wire is bounded and checked: a malformed package
// is a RtdeError naming the package's type and what is wrong.
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace pbnbv::driver::rtde {

inline constexpr uint16_t kPort = 30004;
inline constexpr uint16_t kProtocolVersion = 2;
// The largest package either side accepts, bytes (the protocol allows 65,535; the driver's
// recipes and the controller's text messages stay under 1 kB).
inline constexpr std::size_t kMaxPackageSize = 4096;
inline constexpr std::size_t kHeaderSize = 3;

// Package types (the uint8 after the size).
enum PackageType : uint8_t {
  kRequestProtocolVersion = 'V',  // 86
  kGetUrControlVersion = 'v',     // 118
  kTextMessage = 'M',             // 77
  kDataPackage = 'U',             // 85
  kSetupOutputs = 'O',            // 79
  kSetupInputs = 'I',             // 73
  kStart = 'S',                   // 83
  kPause = 'P',                   // 80
};

// A malformed package or answer; what() names the package type and what is wrong.
struct RtdeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "'V' (request protocol version)": how errors name a package type.
std::string type_label(uint8_t type);

// One package: its type and payload (the header stripped).
struct Package {
  uint8_t type = 0;
  std::vector<uint8_t> payload;
};

// The package's bytes: header + payload. Throws RtdeError when it would exceed kMaxPackageSize.
std::vector<uint8_t> encode(const Package& package);

// Splits a byte stream into packages: feed what the socket gave, then take every complete
// package. A size under the header's or over kMaxPackageSize is an RtdeError (the stream cannot
// be resynchronised: the connection is to be closed).
class Framer {
 public:
  void feed(const uint8_t* data, std::size_t n);
  std::optional<Package> next();
  std::size_t buffered() const { return buffer_.size(); }

 private:
  std::vector<uint8_t> buffer_;
};

// Exactly one package in `bytes` (its size field must equal bytes.size()).
Package decode(const std::vector<uint8_t>& bytes);

// Field types of a recipe, as the controller names them.
enum class Type { kBool, kUint8, kInt32, kUint32, kUint64, kDouble, kVector3d, kVector6d };
const char* type_name(Type t);              // "VECTOR6D"
std::optional<Type> type_of(const std::string& name);  // none for NOT_FOUND, IN_USE and unknown names
std::size_t size_of(Type t);               // bytes on the wire

// One field's value: `number` for the scalar types (integers exactly, up to 2^53), `vector` for
// VECTOR3D / VECTOR6D.
struct Value {
  Type type = Type::kDouble;
  double number = 0;
  std::vector<double> vector;
};
Value scalar(Type t, double number);
Value vector6(const std::array<double, 6>& v);

// A data package ('U'): its recipe id and values in recipe order.
struct Data {
  uint8_t recipe_id = 0;
  std::vector<Value> values;
};

// --- Requests (client -> controller) ---------------------------------------------------------
Package request_protocol_version(uint16_t version = kProtocolVersion);  // 00 05 56 00 02
Package get_urcontrol_version();
// Outputs at `frequency_hz`, inputs: comma-separated names. Throws std::invalid_argument for an
// empty list, an empty name or one holding a comma.
Package setup_outputs(double frequency_hz, const std::vector<std::string>& names);
Package setup_inputs(const std::vector<std::string>& names);
Package start();
Package pause();
// Values must match the types one by one (an integer in its type's range, a vector of its size);
// else std::invalid_argument naming the field.
Package data_package(const Data& data);

// --- Answers (controller -> client) -----------------------------------------------------------
// 'V', 'S', 'P': uint8 accepted. Throws RtdeError for another type or a wrong payload size.
bool parse_accepted(const Package& p, uint8_t expected_type);
struct UrControlVersion {
  uint32_t major = 0, minor = 0, bugfix = 0, build = 0;
};
UrControlVersion parse_urcontrol_version(const Package& p);
// 'O' / 'I' answer: recipe id + the types of the names asked for, as the controller wrote them
// (NOT_FOUND, IN_USE included).
struct SetupAnswer {
  uint8_t recipe_id = 0;
  std::vector<std::string> types;
};
SetupAnswer parse_setup_answer(const Package& p, uint8_t expected_type);
// The recipe's types for `names`: throws RtdeError naming the first variable the controller does
// not know (NOT_FOUND), has given to another client (IN_USE) or typed otherwise than `expected`
// (when given), and for a count that differs from the names'.
std::vector<Type> recipe_types(const SetupAnswer& answer, const std::vector<std::string>& names,
                               const std::vector<Type>& expected = {});
// 'M' (protocol 2): message, source, warning level.
struct TextMessage {
  std::string message, source;
  uint8_t level = 0;
};
TextMessage parse_text_message(const Package& p);
Package text_message(const TextMessage& m);
// 'U' decoded by its recipe. Throws RtdeError for another type, a payload that is not exactly
// the recipe's size, or a recipe id other than `recipe_id`.
Data parse_data_package(const Package& p, uint8_t recipe_id, const std::vector<Type>& recipe);

// --- The controller's side (the twin plays it) -----------------------------------------------
Package accepted_answer(uint8_t type, bool accepted);
Package urcontrol_version_answer(const UrControlVersion& v);
Package setup_answer(uint8_t type, const SetupAnswer& answer);
uint16_t parse_protocol_version_request(const Package& p);
// 'O': frequency + names; 'I': names (frequency 0).
struct SetupRequest {
  double frequency_hz = 0;
  std::vector<std::string> names;
};
SetupRequest parse_setup_request(const Package& p);

}  // namespace pbnbv::driver::rtde
