#include "core/io/file_checks.hpp"

#include <CGAL/IO/PLY.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <iterator>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/base/format.hpp"

namespace pbnbv {

namespace {

// The 1-based line of the file holding byte `offset` (the last line if the file is shorter),
// and its text (at most 60 characters, without the end of line).
std::pair<long, std::string> line_at(const std::string& path, std::uint64_t offset) {
  std::ifstream in(path, std::ios::binary);
  long line = 0;
  std::string text;
  std::uint64_t start = 0;
  for (std::string l; std::getline(in, l);) {
    ++line;
    text = std::move(l);
    start += text.size() + 1;
    if (offset < start) break;
  }
  if (!text.empty() && text.back() == '\r') text.pop_back();
  if (text.size() > 60) text = text.substr(0, 60) + "...";
  return {std::max(line, 1L), text};
}

// Element `name` (or its plural) of a PLY header, or null.
CGAL::IO::internal::PLY_element* find_element(CGAL::IO::internal::PLY_reader& reader, const std::string& name) {
  for (std::size_t i = 0; i < reader.number_of_elements(); ++i) {
    auto& e = reader.element(i);
    if (e.name() == name || e.name() == name + "s") return &e;
  }
  return nullptr;
}

// Whether element `e` has a property called `name`, of any type.
bool has_named(CGAL::IO::internal::PLY_element& e, const char* name) {
  for (std::size_t k = 0; k < e.number_of_properties(); ++k) {
    if (e.property(k)->name() == name) return true;
  }
  return false;
}

}  // namespace

std::string shown(std::string_view word) {
  std::string out(word.substr(0, 40));
  for (char& c : out) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return word.size() > 40 ? out + "..." : out;
}

bool whole_number(std::string_view word, std::uint64_t& n) {
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), n);
  return ec == std::errc() && end == word.data() + word.size();
}

void file_error(const char* ctx, const std::string& path, const std::string& what) {
  throw std::runtime_error(fmt::format("{}: {}: {}", ctx, path, what));
}

void check_input_file(const std::string& path, const char* ctx) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (st.type() == std::filesystem::file_type::not_found) file_error(ctx, path, "file does not exist");
  if (ec) file_error(ctx, path, "cannot access file: " + ec.message());
  if (std::filesystem::is_directory(st)) file_error(ctx, path, "is a directory, not a file");
  // A link to /dev/zero or a FIFO would be read until memory runs out or forever.
  if (!std::filesystem::is_regular_file(st)) file_error(ctx, path, "is not a regular file (a device, FIFO or socket)");
  if (!std::ifstream(path, std::ios::binary)) file_error(ctx, path, std::string("cannot open file: ") + std::strerror(errno));
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size == 0) file_error(ctx, path, "empty file");
  if (!ec && size > kMaxInputFileBytes) {
    file_error(ctx, path, fmt::format("{} bytes, more than the {} bytes (4 GiB) an input file may hold", size, kMaxInputFileBytes));
  }
}

std::string stopped_at(const std::string& path, std::istream& in, bool whole_lines) {
  in.clear();
  const std::streamoff pos = in.tellg();
  if (pos < 0 || (pos == 0 && whole_lines)) return "at the start of the file";
  const auto [line, text] = line_at(path, static_cast<std::uint64_t>(whole_lines ? pos - 1 : pos));
  return fmt::format("at line {}: '{}'", line, text);
}

namespace {

// A PLY file's layout as its header declares it: the format and each element's count and
// properties (a scalar's size in bytes, or a list's count and entry sizes).
struct PlyLayout {
  struct Property {
    int bytes = 0;        // a scalar's, or a list entry's
    int count_bytes = 0;  // a list's count; 0 for a scalar
    bool count_signed = false;
  };
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::vector<Property> properties;
  };
  std::string format;  // ascii, binary_little_endian or binary_big_endian
  std::vector<Element> elements;
};

// The size in bytes of PLY type `type`, and whether it is a signed integer; 0 for an unknown type.
int ply_type_bytes(const std::string& type, bool* is_signed = nullptr, bool* integer = nullptr) {
  static const struct {
    const char* name;
    int bytes;
    bool is_signed, integer;
  } kTypes[] = {{"char", 1, true, true},     {"int8", 1, true, true},    {"uchar", 1, false, true},
                {"uint8", 1, false, true},   {"short", 2, true, true},   {"int16", 2, true, true},
                {"ushort", 2, false, true},  {"uint16", 2, false, true}, {"int", 4, true, true},
                {"int32", 4, true, true},    {"uint", 4, false, true},   {"uint32", 4, false, true},
                {"float", 4, true, false},   {"float32", 4, true, false}, {"double", 8, true, false},
                {"float64", 8, true, false}};
  for (const auto& t : kTypes) {
    if (type == t.name) {
      if (is_signed) *is_signed = t.is_signed;
      if (integer) *integer = t.integer;
      return t.bytes;
    }
  }
  return 0;
}

// The header's lines read the way CGAL's reader splits them, within 1 MB; the stream is left at
// the first byte of the body. What CGAL 5.5 assumes of a header without checking it, each found
// by fuzz_mesh_file: a "property" line before any "element" line makes it write through the
// back() of an empty vector; an element count of -4 becomes 2^64 - 4 items, read for ever from
// the end of the file. So every element count is a whole number no larger than the file (an item
// takes at least a byte), and every list counted in an integer type.
PlyLayout read_ply_layout(std::istream& in, const std::string& path, const char* ctx, std::uintmax_t size) {
  constexpr std::size_t kMaxHeaderBytes = std::size_t{1} << 20;
  PlyLayout layout;
  std::size_t bytes = 0;
  long line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    bytes += line.size() + 1;
    if (bytes > kMaxHeaderBytes) file_error(ctx, path, "PLY header longer than 1 MB without end_header");
    std::istringstream iss(line);
    std::string keyword;
    if (!(iss >> keyword)) continue;
    if (keyword == "end_header") return layout;
    if (keyword == "format") iss >> layout.format;
    if (keyword == "element") {
      PlyLayout::Element& e = layout.elements.emplace_back();
      std::string count;
      iss >> e.name >> count;
      // CGAL checks the first element of a name and reads the last (found by fuzz_cloud_file: a
      // second vertex element with uchar coordinates, read through a null pointer).
      for (std::size_t k = 0; k + 1 < layout.elements.size(); ++k) {
        if (layout.elements[k].name == e.name) {
          file_error(ctx, path, fmt::format("PLY header line {}: a second element '{}'", line_number, shown(e.name)));
        }
      }
      if (!whole_number(count, e.count)) {
        file_error(ctx, path, fmt::format("PLY header line {}: element '{}' has count '{}', not a whole number", line_number,
                                          shown(e.name), shown(count)));
      }
      if (e.count > size) {
        file_error(ctx, path, fmt::format("PLY header line {}: element '{}' declares {} items, more than a file of {} bytes "
                                          "can hold", line_number, shown(e.name), e.count, size));
      }
    }
    if (keyword != "property") continue;
    if (layout.elements.empty()) file_error(ctx, path, fmt::format("PLY header line {}: a property before any element", line_number));
    PlyLayout::Property& prop = layout.elements.back().properties.emplace_back();
    std::string type, count_type, entry_type;
    iss >> type;
    if (type == "list") {
      iss >> count_type >> entry_type;
      bool integer = false;
      prop.count_bytes = ply_type_bytes(count_type, &prop.count_signed, &integer);
      if (prop.count_bytes == 0 || !integer) {
        file_error(ctx, path, fmt::format("PLY header line {}: a list counted in '{}', not an integer type", line_number,
                                          shown(count_type)));
      }
      type = entry_type;
    }
    prop.bytes = ply_type_bytes(type);
    if (prop.bytes == 0) file_error(ctx, path, fmt::format("PLY header line {}: unknown property type '{}'", line_number, shown(type)));
  }
  return layout;  // no end_header: CGAL's reader names it
}

// The body of a PLY file walked item by item before CGAL reads it: CGAL reads a list's count and
// allocates for it before reading the entries (a 32-bit count from a few hostile bytes: up to 32
// GB). Every list's count here fits in what is left of the file (an entry takes its size in a
// binary file, two bytes in an ASCII one). A body cut short is left to CGAL's reader to name.
void check_ply_lists(std::istream& in, const std::string& path, const char* ctx, const PlyLayout& layout,
                     std::uintmax_t size) {
  const bool ascii = layout.format == "ascii";
  const bool big = layout.format == "binary_big_endian";
  if (!ascii && !big && layout.format != "binary_little_endian") return;  // CGAL names the format
  bool lists = false;
  for (const auto& e : layout.elements) {
    for (const auto& p : e.properties) lists = lists || p.count_bytes > 0;
  }
  if (!lists) return;
  // The position is counted here, not asked of the stream: tellg and seekg are a system call each
  // on a file stream, and a mesh of 300,000 faces walked that way took seconds (ignore, get and
  // read take the stream's buffer).
  std::uintmax_t pos = static_cast<std::uintmax_t>(in.tellg());
  const auto skip = [&](std::size_t n) {  // binary: n bytes
    in.ignore(static_cast<std::streamsize>(n));
    pos += static_cast<std::uintmax_t>(in.gcount());
    return static_cast<std::size_t>(in.gcount()) == n;
  };
  std::string token;
  const auto next_token = [&] {  // ASCII: the next word, up to the whitespace after it
    token.clear();
    int c = in.get();
    while (c != std::char_traits<char>::eof() && std::isspace(c)) {
      ++pos;
      c = in.get();
    }
    if (c == std::char_traits<char>::eof()) return false;
    for (; c != std::char_traits<char>::eof() && !std::isspace(c); c = in.get()) {
      ++pos;
      token.push_back(static_cast<char>(c));
    }
    if (c != std::char_traits<char>::eof()) in.unget();
    in.clear();
    return true;
  };
  for (const auto& e : layout.elements) {
    for (std::uint64_t item = 0; item < e.count; ++item) {
      for (const auto& p : e.properties) {
        if (p.count_bytes == 0) {  // a scalar
          if (ascii ? !next_token() : !skip(static_cast<std::size_t>(p.bytes))) return;
          continue;
        }
        std::int64_t count = 0;
        if (ascii) {
          if (!next_token()) return;
          const auto [end, err] = std::from_chars(token.data(), token.data() + token.size(), count);
          if (err != std::errc() || end != token.data() + token.size()) return;  // CGAL names it
        } else {
          unsigned char b[4] = {};
          if (!in.read(reinterpret_cast<char*>(b), p.count_bytes)) return;
          pos += static_cast<std::uintmax_t>(p.count_bytes);
          std::uint32_t u = 0;
          for (int k = 0; k < p.count_bytes; ++k) u = (u << 8) | b[big ? k : p.count_bytes - 1 - k];
          const int bits = 8 * p.count_bytes;
          count = (p.count_signed && bits < 64 && (u >> (bits - 1)) != 0) ? static_cast<std::int64_t>(u) - (std::int64_t{1} << bits)
                                                                          : static_cast<std::int64_t>(u);
        }
        const std::uintmax_t left = size > pos ? size - pos : 0;
        const std::uintmax_t most = left / (ascii ? 2 : static_cast<std::uintmax_t>(p.bytes));
        // A polygon's worth past the end (at most 65,535 entries) is a file cut short: CGAL's
        // reader says so.
        if (count >= 0 && count <= 65535 && static_cast<std::uintmax_t>(count) > most) return;
        if (count < 0 || static_cast<std::uintmax_t>(count) > most) {
          file_error(ctx, path, fmt::format("PLY element '{}' item {}: a list of {} entries, more than the {} bytes left in "
                                            "the file can hold", shown(e.name), item, count, left));
        }
        if (!ascii) {
          if (!skip(static_cast<std::size_t>(count) * static_cast<std::size_t>(p.bytes))) return;
          continue;
        }
        for (std::int64_t k = 0; k < count; ++k) {
          if (!next_token()) return;
        }
      }
    }
  }
}

// Checks the header and the body's lists (read_ply_layout and check_ply_lists say what and why),
// then puts the stream back where it was.
void precheck_ply(std::istream& in, const std::string& path, const char* ctx) {
  const std::streampos start = in.tellg();
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return;
  const PlyLayout layout = read_ply_layout(in, path, ctx, size);
  if (in) check_ply_lists(in, path, ctx, layout, size);
  in.clear();
  in.seekg(start);
}

}  // namespace

PlyHeader check_ply_header(std::istream& in, const std::string& path, const char* ctx, bool faces) {
  precheck_ply(in, path, ctx);
  CGAL::IO::internal::PLY_reader reader(false);
  if (!reader.init(in)) {
    file_error(ctx, path, "not a PLY file, or a malformed PLY header: CGAL's PLY reader stopped " + stopped_at(path, in, true));
  }
  PlyHeader h;
  auto* vertex = find_element(reader, "vertex");
  if (!vertex) file_error(ctx, path, "PLY has no 'vertex' element");
  h.vertices = vertex->number_of_items();
  // A coordinate or a normal's component of another type is read through a null pointer.
  for (const char* c : {"x", "y", "z", "nx", "ny", "nz"}) {
    const bool normal = c[0] == 'n';
    if (!normal && !has_named(*vertex, c)) file_error(ctx, path, "PLY vertex element lacks x, y or z");
    // has_property<double> accepts a float or a double property.
    if (has_named(*vertex, c) && !vertex->has_property<double>(c)) {
      file_error(ctx, path, fmt::format("PLY vertex property '{}' is not float or double", c));
    }
  }
  auto* face = faces ? find_element(reader, "face") : nullptr;
  if (face) {
    h.faces = face->number_of_items();
    bool ok = false;
    for (const char* list : {"vertex_indices", "vertex_index"}) {
      ok = ok || face->has_property<std::vector<std::int32_t>>(list) ||
           face->has_property<std::vector<std::uint32_t>>(list);
    }
    if (!ok) file_error(ctx, path, "PLY face element has no vertex_indices list of int or uint");
  }
  return h;
}

std::string ply_failure(const PlyHeader& header, const std::string& path, std::istream& in) {
  in.clear();
  const std::streamoff pos = in.tellg();
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && pos >= 0 && static_cast<std::uintmax_t>(pos) >= size) {
    return fmt::format("truncated PLY: the file ends before the {} vertices{} its header declares were read",
                       header.vertices, header.faces ? fmt::format(" and {} faces", header.faces) : "");
  }
  return "cannot read the PLY body: CGAL::IO::read_PLY stopped " + stopped_at(path, in, false);
}

}  // namespace pbnbv
