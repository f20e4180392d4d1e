#include "core/io/file_checks.hpp"

#include <CGAL/IO/PLY.h>

#include <algorithm>
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

// Throws "<ctx>: <path>: <what>".
[[noreturn]] void fail(const char* ctx, const std::string& path, const std::string& what) {
  throw std::runtime_error(fmt::format("{}: {}: {}", ctx, path, what));
}

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

void check_input_file(const std::string& path, const char* ctx) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (st.type() == std::filesystem::file_type::not_found) fail(ctx, path, "file does not exist");
  if (ec) fail(ctx, path, "cannot access file: " + ec.message());
  if (std::filesystem::is_directory(st)) fail(ctx, path, "is a directory, not a file");
  // A link to /dev/zero or a FIFO would be read until memory runs out or forever.
  if (!std::filesystem::is_regular_file(st)) fail(ctx, path, "is not a regular file (a device, FIFO or socket)");
  if (!std::ifstream(path, std::ios::binary)) fail(ctx, path, std::string("cannot open file: ") + std::strerror(errno));
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size == 0) fail(ctx, path, "empty file");
  if (!ec && size > kMaxInputFileBytes) {
    fail(ctx, path, fmt::format("{} bytes, more than the {} bytes (4 GiB) an input file may hold", size, kMaxInputFileBytes));
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

// What CGAL's PLY reader assumes of a header without checking it (CGAL 5.5): a "property" line
// before any "element" line makes it write through the back() of an empty vector (found by
// fuzz_mesh_file). The header's lines are read the way the reader splits them, within 1 MB,
// and the stream put back where it was.
void precheck_ply_header(std::istream& in, const std::string& path, const char* ctx) {
  constexpr std::size_t kMaxHeaderBytes = std::size_t{1} << 20;
  const std::streampos start = in.tellg();
  std::size_t bytes = 0;
  long line_number = 0;
  bool element = false;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    bytes += line.size() + 1;
    if (bytes > kMaxHeaderBytes) fail(ctx, path, "PLY header longer than 1 MB without end_header");
    std::istringstream iss(line);
    std::string keyword;
    if (!(iss >> keyword)) continue;
    if (keyword == "end_header") break;
    if (keyword == "element") element = true;
    if (keyword == "property" && !element) {
      fail(ctx, path, fmt::format("PLY header line {}: a property before any element", line_number));
    }
  }
  in.clear();
  in.seekg(start);
}

}  // namespace

PlyHeader check_ply_header(std::istream& in, const std::string& path, const char* ctx, bool faces) {
  precheck_ply_header(in, path, ctx);
  CGAL::IO::internal::PLY_reader reader(false);
  if (!reader.init(in)) {
    fail(ctx, path, "not a PLY file, or a malformed PLY header: CGAL's PLY reader stopped " + stopped_at(path, in, true));
  }
  PlyHeader h;
  auto* vertex = find_element(reader, "vertex");
  if (!vertex) fail(ctx, path, "PLY has no 'vertex' element");
  h.vertices = vertex->number_of_items();
  for (const char* c : {"x", "y", "z"}) {
    if (!has_named(*vertex, c)) fail(ctx, path, "PLY vertex element lacks x, y or z");
    // has_property<double> accepts a float or a double property.
    if (!vertex->has_property<double>(c)) {
      fail(ctx, path, fmt::format("PLY vertex property '{}' is not float or double", c));
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
    if (!ok) fail(ctx, path, "PLY face element has no vertex_indices list of int or uint");
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
