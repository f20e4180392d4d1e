#pragma once
// What CGAL's file readers leave unsaid, shared by the mesh and cloud readers of this folder:
// where a reader stopped, and the checks of a PLY header CGAL needs done before it reads.
#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>
#include <string_view>

namespace pbnbv {

// The largest mesh, cloud or config file read (4 GiB): far above any real scan's, far below
// what a reader's memory would stand.
inline constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{4} << 30;

// Throws std::runtime_error "<ctx>: <path>: <what>", the readers' form of an error in a file.
[[noreturn]] void file_error(const char* ctx, const std::string& path, const std::string& what);

// Throws std::runtime_error "<ctx>: <path>: ..." unless `path` names an existing, non-empty
// regular file (not a directory, device, FIFO or socket, also behind a link) of at most
// kMaxInputFileBytes that can be opened for reading.
void check_input_file(const std::string& path, const char* ctx);

// Where a reader that failed on `in` (a text file at `path`) stopped: "at line N: '<text>'".
// A reader that reads whole lines stops after the line it could not read (`whole_lines`: the
// line of the last byte consumed); one that reads token by token stops at the token (the line
// of the next byte). Clears the stream's error state.
std::string stopped_at(const std::string& path, std::istream& in, bool whole_lines);

// The counts a PLY header declares.
struct PlyHeader {
  std::size_t vertices = 0;
  std::size_t faces = 0;
};

// `word`, read from a file, as an error message shows it: at most 40 bytes (then "..."), any
// byte that is not printable ASCII shown as '?'.
std::string shown(std::string_view word);

// `word` as a whole number (decimal digits only, all of it, within 64 bits) in `n`, or false.
bool whole_number(std::string_view word, std::uint64_t& n);

// Reads the PLY header on `in` (CGAL's PLY header reader) and checks that it has a vertex
// element with x, y and z of type float or double (CGAL 5.5's read_PLY reads any other type
// through a null pointer) and, with `faces`, that a face element, if any, has a vertex_indices
// (or vertex_index) list of int or uint (the types CGAL reads). Before that, what CGAL does not
// check: every element count within the file's size, every list counted in an integer type and
// every list in the body no longer than what is left of the file. Throws std::runtime_error
// "<ctx>: <path>: ..." saying what is wrong. Leaves `in` after the header.
PlyHeader check_ply_header(std::istream& in, const std::string& path, const char* ctx, bool faces);

// Why CGAL's read_PLY failed on `in` after `header` was checked: a binary body ends early
// (truncated), a text one stopped at a line it could not read.
std::string ply_failure(const PlyHeader& header, const std::string& path, std::istream& in);

}  // namespace pbnbv
