// The message set's own description (lcmtypes/*.lcm, embedded at build time), and a walk
// of an encoded message that says where each field lies in its bytes.
//
// fault_inject crafts hostile packets by editing a valid encoding in place: a string's
// length prefix set to 0 or -1, an array's count member set to a huge value, a double set
// to NaN. To find those bytes for every type without a hand-kept table that would drift
// from lcmtypes/, it reads the .lcm files (LCM 1.3.1 generates no reflection for C++) and
// follows LCM's encoding: an 8-byte fingerprint, then the fields in order, big-endian;
// a string as an int32 length (with its NUL) and the bytes; nested structs without a
// fingerprint; arrays sized by constants or by earlier integer members.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace rover::fault {

struct FieldSpec {
  std::string type;               // "int32_t", "string", "image_t", ...
  std::string name;
  std::vector<std::string> dims;  // each a number or the name of an earlier member
};

struct StructSpec {
  std::string name;
  std::vector<FieldSpec> fields;
  std::vector<std::pair<std::string, std::int64_t>> constants;  // const NAME = value
};

class Schema {
 public:
  // Parses the text of .lcm files. Throws std::runtime_error naming the file and token.
  static Schema Parse(const std::vector<std::pair<std::string, std::string>>& named_texts);
  // The project's message set, embedded from lcmtypes/ when this tool was built.
  static const Schema& Embedded();

  bool Has(const std::string& type) const { return structs_.count(type) > 0; }
  const StructSpec& Get(const std::string& type) const;  // throws when unknown
  std::vector<std::string> TypeNames() const;

 private:
  std::map<std::string, StructSpec> structs_;
};

// Where a field of interest lies in an encoded message.
enum class FieldKind {
  kStringLength,  // int32 length prefix of a string (counts its NUL)
  kCount,         // an integer member that sizes an array
  kDouble,        // one double (an array gives one location per element)
  kEnum,          // an int8 member with constants NAME_* named after it (state, type, ...)
  kTime,          // an int64 member named utime or *_utime
};

struct FieldLocation {
  FieldKind kind;
  std::string path;       // "left.size", "zones[1].name", "covariance"
  std::size_t offset;     // of its first byte in the encoded message
  std::size_t width;      // bytes: 4 for int32, 8 for int64/double, 1 for int8
  bool top_level = false; // a member of the message itself, not of a nested struct
};

struct Layout {
  std::vector<FieldLocation> fields;
  std::size_t end = 0;    // bytes the walk consumed (the encoded size)
};

// Walks `size` bytes holding an encoded `type` (fingerprint included). Throws
// std::runtime_error if the bytes do not hold one (it is meant for our own encodings).
Layout Walk(const Schema& schema, const std::string& type, const std::uint8_t* data, std::size_t size);

// Big-endian field edits, as LCM encodes.
void PutInt32(std::vector<std::uint8_t>& bytes, std::size_t offset, std::int32_t value);
void PutInt64(std::vector<std::uint8_t>& bytes, std::size_t offset, std::int64_t value);
void PutDouble(std::vector<std::uint8_t>& bytes, std::size_t offset, double value);
std::int64_t GetInt(const std::uint8_t* data, std::size_t width);

// The embedded .lcm texts, (file name, text) (generated source).
const std::vector<std::pair<std::string, std::string>>& EmbeddedSchemaTexts();

}  // namespace rover::fault
