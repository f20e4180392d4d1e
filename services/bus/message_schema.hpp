#pragma once
// The layout of every message of the contract as lcmtypes/*.lcm declares it: for each struct its
// encoded members in order, their kind and array dimensions. The table is generated at build time
// from the .lcm files (schema/message_schema_gen.cpp), so it cannot drift from what lcm-gen's
// decoders read; message_guard walks an encoding with it before any decoder runs.
#include <cstdint>
#include <string_view>
#include <vector>

namespace pbnbv::bus {

enum class FieldKind : uint8_t { kInt8, kInt16, kInt32, kInt64, kFloat, kDouble, kString, kBoolean, kByte, kStruct };

// One dimension of an array member: a literal length, or the index of an earlier integer member
// of the same struct that holds it.
struct ArrayDim {
  int64_t fixed = -1;    // the length when literal, else -1
  int count_field = -1;  // the member holding the length, else -1
};

struct FieldSchema {
  std::string_view name;
  FieldKind kind;
  int nested = -1;             // index into message_schemas() when kind == kStruct
  std::vector<ArrayDim> dims;  // empty: a single value
};

struct MessageSchema {
  std::string_view name;  // the struct's name without the package ("depth_frame_t")
  std::vector<FieldSchema> fields;
};

// Every struct of lcmtypes/, sorted by name (generated).
const std::vector<MessageSchema>& message_schemas();

// The schema of `type_name`, or nullptr when the contract has no such struct.
const MessageSchema* find_schema(std::string_view type_name);

}  // namespace pbnbv::bus
