#include "fault_inject/lcm_schema.hpp"

#include <cctype>
#include <cstring>
#include <set>
#include <stdexcept>

namespace rover::fault {
namespace {

// Tokens of an .lcm file: identifiers (with dots), numbers, and single punctuation marks.
std::vector<std::string> Tokenize(const std::string& text) {
  std::vector<std::string> tokens;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      i = text.find('\n', i);
      if (i == std::string::npos) break;
    } else if (text.compare(i, 2, "/*") == 0) {
      i = text.find("*/", i);
      if (i == std::string::npos) break;
      i += 2;
    } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-') {
      std::size_t j = i;
      while (j < text.size() && (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_' ||
                                 text[j] == '.' || text[j] == '-'))
        ++j;
      tokens.push_back(text.substr(i, j - i));
      i = j;
    } else {
      tokens.emplace_back(1, c);
      ++i;
    }
  }
  return tokens;
}

class Parser {
 public:
  Parser(std::string file, std::vector<std::string> tokens) : file_(std::move(file)), t_(std::move(tokens)) {}

  void ParseInto(std::map<std::string, StructSpec>& out) {
    while (i_ < t_.size()) {
      const std::string word = Next();
      if (word == "package") {
        Next();
        Expect(";");
      } else if (word == "struct") {
        StructSpec s = ParseStruct();
        out[s.name] = std::move(s);
      } else {
        Fail("unexpected '" + word + "' (expected package or struct)");
      }
    }
  }

 private:
  StructSpec ParseStruct() {
    StructSpec s;
    s.name = Next();
    Expect("{");
    while (Peek() != "}") {
      if (Peek() == "const") {
        Next();
        Next();  // type
        for (;;) {
          const std::string name = Next();
          Expect("=");
          s.constants.emplace_back(name, std::stoll(Next(), nullptr, 0));
          if (Peek() == ",") {
            Next();
            continue;
          }
          Expect(";");
          break;
        }
        continue;
      }
      FieldSpec f;
      f.type = Unqualified(Next());
      f.name = Next();
      while (Peek() == "[") {
        Next();
        f.dims.push_back(Next());
        Expect("]");
      }
      Expect(";");
      s.fields.push_back(std::move(f));
    }
    Expect("}");
    return s;
  }

  static std::string Unqualified(const std::string& type) {
    const auto dot = type.rfind('.');
    return dot == std::string::npos ? type : type.substr(dot + 1);
  }
  const std::string& Peek() {
    if (i_ >= t_.size()) Fail("unexpected end of file");
    return t_[i_];
  }
  std::string Next() {
    const std::string t = Peek();
    ++i_;
    return t;
  }
  void Expect(const std::string& want) {
    const std::string got = Next();
    if (got != want) Fail("'" + got + "' (expected '" + want + "')");
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw std::runtime_error(file_ + ": token " + std::to_string(i_) + ": " + what);
  }

  std::string file_;
  std::vector<std::string> t_;
  std::size_t i_ = 0;
};

std::size_t PrimitiveWidth(const std::string& type) {
  if (type == "int8_t" || type == "byte" || type == "boolean") return 1;
  if (type == "int16_t") return 2;
  if (type == "int32_t" || type == "float") return 4;
  if (type == "int64_t" || type == "double") return 8;
  return 0;  // string or a struct
}

bool IsInteger(const std::string& type) {
  return type == "int8_t" || type == "int16_t" || type == "int32_t" || type == "int64_t" || type == "byte";
}

bool IsTimeName(const std::string& name) {
  return name == "utime" || (name.size() > 6 && name.compare(name.size() - 6, 6, "_utime") == 0);
}

std::string Upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// An int8 member is an enum when the struct has constants named after it: `state` and
// STATE_OK, `type` and TYPE_ARC.
bool IsEnum(const StructSpec& s, const FieldSpec& f) {
  if (f.type != "int8_t" || !f.dims.empty()) return false;
  const std::string prefix = Upper(f.name) + "_";
  for (const auto& [name, value] : s.constants)
    if (name.rfind(prefix, 0) == 0) return true;
  return false;
}

class Walker {
 public:
  Walker(const Schema& schema, const std::uint8_t* data, std::size_t size)
      : schema_(schema), d_(data), size_(size) {}

  Layout Run(const std::string& type) {
    Need(8);  // the fingerprint
    pos_ = 8;
    Struct(schema_.Get(type), "", true);
    layout_.end = pos_;
    return layout_;
  }

 private:
  void Need(std::size_t n) const {
    if (pos_ + n > size_) {
      throw std::runtime_error("encoded message ends at byte " + std::to_string(size_) +
                               " (a field needs " + std::to_string(n) + " bytes at " + std::to_string(pos_) + ")");
    }
  }

  void Struct(const StructSpec& s, const std::string& prefix, bool top) {
    std::set<std::string> sizing;  // members that size an array
    for (const auto& f : s.fields)
      for (const auto& dim : f.dims)
        if (!dim.empty() && !std::isdigit(static_cast<unsigned char>(dim[0]))) sizing.insert(dim);
    std::map<std::string, std::int64_t> ints;
    for (const auto& f : s.fields) {
      std::int64_t count = 1;
      for (const auto& dim : f.dims) {
        std::int64_t n = 0;
        if (std::isdigit(static_cast<unsigned char>(dim[0]))) {
          n = std::stoll(dim);
        } else if (auto it = ints.find(dim); it != ints.end()) {
          n = it->second;
        } else {
          throw std::runtime_error(s.name + "." + f.name + ": dimension '" + dim + "' is not an earlier integer member");
        }
        if (n < 0) throw std::runtime_error(s.name + "." + f.name + ": negative dimension " + std::to_string(n));
        count *= n;
      }
      const std::string path = prefix + f.name;
      const std::size_t width = PrimitiveWidth(f.type);
      for (std::int64_t k = 0; k < count; ++k) {
        if (f.type == "string") {
          Need(4);
          const std::int64_t length = GetInt(d_ + pos_, 4);
          layout_.fields.push_back({FieldKind::kStringLength, path, pos_, 4, top});
          pos_ += 4;
          if (length < 1) throw std::runtime_error(path + ": string length " + std::to_string(length));
          Need(static_cast<std::size_t>(length));
          pos_ += static_cast<std::size_t>(length);
        } else if (width == 0) {
          const std::string element = f.dims.empty() ? path + "." : path + "[" + std::to_string(k) + "].";
          Struct(schema_.Get(f.type), element, false);
        } else {
          Need(width);
          if (f.dims.empty() && IsInteger(f.type)) {
            const std::int64_t value = GetInt(d_ + pos_, width);
            ints[f.name] = value;
            if (sizing.count(f.name)) layout_.fields.push_back({FieldKind::kCount, path, pos_, width, top});
            if (IsEnum(s, f)) layout_.fields.push_back({FieldKind::kEnum, path, pos_, width, top});
            if (f.type == "int64_t" && IsTimeName(f.name))
              layout_.fields.push_back({FieldKind::kTime, path, pos_, width, top});
          }
          if (f.type == "double") layout_.fields.push_back({FieldKind::kDouble, path, pos_, width, top});
          pos_ += width;
        }
      }
    }
  }

  const Schema& schema_;
  const std::uint8_t* d_;
  std::size_t size_;
  std::size_t pos_ = 0;
  Layout layout_;
};

}  // namespace

Schema Schema::Parse(const std::vector<std::pair<std::string, std::string>>& named_texts) {
  Schema schema;
  for (const auto& [name, text] : named_texts) Parser(name, Tokenize(text)).ParseInto(schema.structs_);
  return schema;
}

const Schema& Schema::Embedded() {
  static const Schema schema = Parse(EmbeddedSchemaTexts());
  return schema;
}

const StructSpec& Schema::Get(const std::string& type) const {
  const auto it = structs_.find(type);
  if (it == structs_.end()) throw std::runtime_error("no message type " + type + " in lcmtypes/");
  return it->second;
}

std::vector<std::string> Schema::TypeNames() const {
  std::vector<std::string> names;
  for (const auto& [name, spec] : structs_) names.push_back(name);
  return names;
}

Layout Walk(const Schema& schema, const std::string& type, const std::uint8_t* data, std::size_t size) {
  return Walker(schema, data, size).Run(type);
}

std::int64_t GetInt(const std::uint8_t* data, std::size_t width) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < width; ++i) v = (v << 8) | data[i];
  // Sign-extend from `width` bytes.
  if (width < 8 && (v >> (8 * width - 1)) & 1) v |= ~std::uint64_t{0} << (8 * width);
  return static_cast<std::int64_t>(v);
}

void PutInt32(std::vector<std::uint8_t>& bytes, std::size_t offset, std::int32_t value) {
  const auto v = static_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) bytes.at(offset + i) = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

void PutInt64(std::vector<std::uint8_t>& bytes, std::size_t offset, std::int64_t value) {
  const auto v = static_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) bytes.at(offset + i) = static_cast<std::uint8_t>(v >> (56 - 8 * i));
}

void PutDouble(std::vector<std::uint8_t>& bytes, std::size_t offset, double value) {
  std::int64_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  PutInt64(bytes, offset, bits);
}

}  // namespace rover::fault
