// pbnbv-message-schema-gen: reads the contract's .lcm files and writes the table of their layouts
// (bus/message_schema.hpp) as C++, so the bus can walk a message's encoding before any generated
// decoder sizes a vector from it. Run by CMake at build time; the table lives in the build folder.
//
//   pbnbv-message-schema-gen OUT.cpp FILE.lcm...
//
// Understands what LCM's grammar allows in a struct: primitive and struct members, arrays of fixed
// or member-given length (any number of dimensions), constants (skipped: they are not encoded),
// comments. Anything else is refused naming the file and line, so a contract change the walker
// cannot follow stops the build instead of passing unchecked.
#include <cctype>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Token {
  std::string text;
  int line = 0;
};

struct Dim {
  long fixed = -1;       // a literal length, or -1
  std::string member;    // the member holding the length, when not fixed
};

struct Member {
  std::string type;      // primitive name or struct name (package stripped)
  std::string name;
  std::vector<Dim> dims;
  int line = 0;
};

struct Struct {
  std::string name;
  std::string file;
  std::vector<Member> members;
};

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw std::runtime_error(file + ":" + std::to_string(line) + ": " + what);
}

std::vector<Token> tokenize(const std::string& text, const std::string& file) {
  std::vector<Token> out;
  int line = 1;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      while (i < text.size() && text[i] != '\n') ++i;
    } else if (text.compare(i, 2, "/*") == 0) {
      const std::size_t end = text.find("*/", i + 2);
      if (end == std::string::npos) fail(file, line, "comment not closed");
      for (std::size_t k = i; k < end; ++k) line += text[k] == '\n';
      i = end + 2;
    } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' || c == '+') {
      std::size_t j = i;
      while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_' ||
                                 text[j] == '.' || text[j] == '-' || text[j] == '+')) {
        ++j;
      }
      out.push_back({text.substr(i, j - i), line});
      i = j;
    } else if (std::string("{}[];=,").find(c) != std::string::npos) {
      out.push_back({std::string(1, c), line});
      ++i;
    } else {
      fail(file, line, std::string("unexpected character '") + c + "'");
    }
  }
  return out;
}

const std::map<std::string, std::string> kPrimitives = {
    {"int8_t", "kInt8"},   {"int16_t", "kInt16"}, {"int32_t", "kInt32"},   {"int64_t", "kInt64"},
    {"float", "kFloat"},   {"double", "kDouble"}, {"string", "kString"},   {"boolean", "kBoolean"},
    {"byte", "kByte"}};
const std::set<std::string> kCountTypes = {"int8_t", "int16_t", "int32_t", "int64_t"};

bool is_number(const std::string& s) {
  return !s.empty() && std::isdigit(static_cast<unsigned char>(s[0]));
}

std::vector<Struct> parse(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::vector<Token> t = tokenize(ss.str(), file);
  std::size_t i = 0;
  const auto at_end = [&] { return i >= t.size(); };
  const auto line = [&] { return at_end() ? (t.empty() ? 1 : t.back().line) : t[i].line; };
  const auto next = [&]() -> const std::string& {
    if (at_end()) fail(file, line(), "unexpected end of file");
    return t[i++].text;
  };
  const auto expect = [&](const std::string& want) {
    const int l = line();
    const std::string& got = next();
    if (got != want) fail(file, l, "expected '" + want + "', found '" + got + "'");
  };
  std::vector<Struct> structs;
  while (!at_end()) {
    const int l = line();
    const std::string word = next();
    if (word == "package") {
      next();
      expect(";");
    } else if (word == "struct") {
      Struct s;
      s.name = next();
      s.file = file;
      expect("{");
      while (!at_end() && t[i].text != "}") {
        Member m;
        m.line = line();
        const std::string first = next();
        if (first == "const") {  // const TYPE NAME = VALUE (, NAME = VALUE)* ;  not encoded
          while (next() != ";") {
          }
          continue;
        }
        m.type = first.substr(first.rfind('.') == std::string::npos ? 0 : first.rfind('.') + 1);
        m.name = next();
        while (!at_end() && t[i].text == "[") {
          ++i;
          Dim d;
          const std::string size = next();
          if (is_number(size)) d.fixed = std::stol(size);
          else d.member = size;
          expect("]");
          m.dims.push_back(d);
        }
        expect(";");
        s.members.push_back(m);
      }
      expect("}");
      structs.push_back(s);
    } else {
      fail(file, l, "expected 'package' or 'struct', found '" + word + "' (the schema generator knows no more)");
    }
  }
  return structs;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: pbnbv-message-schema-gen OUT.cpp FILE.lcm...\n";
    return 2;
  }
  try {
    std::map<std::string, Struct> by_name;  // sorted: the table's order
    for (int a = 2; a < argc; ++a) {
      for (Struct& s : parse(argv[a])) {
        if (by_name.count(s.name)) fail(argv[a], 1, "struct " + s.name + " is defined twice");
        by_name[s.name] = s;
      }
    }
    std::map<std::string, int> index;
    for (const auto& [name, s] : by_name) index[name] = static_cast<int>(index.size());

    std::ostringstream out;
    out << "// Generated by pbnbv-message-schema-gen from lcmtypes/*.lcm. Do not edit.\n"
        << "#include \"bus/message_schema.hpp\"\n\nnamespace pbnbv::bus {\n\n"
        << "const std::vector<MessageSchema>& message_schemas() {\n"
        << "  static const std::vector<MessageSchema> schemas = {\n";
    for (const auto& [name, s] : by_name) {
      out << "    {\"" << name << "\", {\n";
      std::map<std::string, int> earlier;  // member name -> index, integers only
      for (std::size_t k = 0; k < s.members.size(); ++k) {
        const Member& m = s.members[k];
        std::string kind;
        int nested = -1;
        if (kPrimitives.count(m.type)) {
          kind = kPrimitives.at(m.type);
        } else if (index.count(m.type)) {
          kind = "kStruct";
          nested = index.at(m.type);
          if (m.type == name) fail(s.file, m.line, name + " contains itself");
        } else {
          fail(s.file, m.line, "unknown type '" + m.type + "' of member " + m.name);
        }
        out << "      {\"" << m.name << "\", FieldKind::" << kind << ", " << nested << ", {";
        for (const Dim& d : m.dims) {
          if (d.fixed >= 0) {
            out << "{" << d.fixed << ", -1}, ";
          } else {
            if (!earlier.count(d.member)) {
              fail(s.file, m.line, "the length of " + m.name + " is '" + d.member +
                                       "', which is not an integer member declared before it");
            }
            out << "{-1, " << earlier.at(d.member) << "}, ";
          }
        }
        out << "}},\n";
        if (kCountTypes.count(m.type) && m.dims.empty()) earlier[m.name] = static_cast<int>(k);
      }
      out << "    }},\n";
    }
    out << "  };\n  return schemas;\n}\n\n}  // namespace pbnbv::bus\n";

    const std::string path = argv[1];
    std::ofstream f(path + ".tmp");
    f << out.str();
    f.close();
    if (!f || std::rename((path + ".tmp").c_str(), path.c_str()) != 0) {
      throw std::runtime_error("cannot write " + path);
    }
  } catch (const std::exception& e) {
    std::cerr << "pbnbv-message-schema-gen: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
