// A minimal JSON emitter for summary.json and metrics.json. Written by hand because the
// project needs only to write a few flat objects, which does not justify a new dependency;
// the output is read back in tests with yaml-cpp (YAML 1.2 reads JSON).
#pragma once

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace rover::tools {

class JsonWriter {
 public:
  JsonWriter& BeginObject() { return Open('{'); }
  JsonWriter& EndObject() { return Close('}'); }
  JsonWriter& BeginArray() { return Open('['); }
  JsonWriter& EndArray() { return Close(']'); }

  JsonWriter& Key(const std::string& key) {
    Separator();
    os_ << Quote(key) << ": ";
    after_key_ = true;
    return *this;
  }
  JsonWriter& Value(const std::string& v) { return Raw(Quote(v)); }
  JsonWriter& Value(const char* v) { return Raw(Quote(v)); }
  JsonWriter& Value(bool v) { return Raw(v ? "true" : "false"); }
  JsonWriter& Value(int v) { return Raw(std::to_string(v)); }
  JsonWriter& Value(long v) { return Raw(std::to_string(v)); }
  JsonWriter& Value(long long v) { return Raw(std::to_string(v)); }
  JsonWriter& Value(double v) { return Raw(Number(v)); }
  JsonWriter& Null() { return Raw("null"); }
  template <class T>
  JsonWriter& Field(const std::string& key, const T& v) {
    Key(key);
    return Value(v);
  }

  std::string str() const { return os_.str() + "\n"; }

  // A JSON number (6 significant digits; null when not finite).
  static std::string Number(double v) {
    if (!std::isfinite(v)) return "null";
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.6g", v);
    return buf;
  }
  // A JSON string literal, escaped.
  static std::string Quote(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
      switch (c) {
        case '"': out += "\\\""; break;
        case '\\': out += "\\\\"; break;
        case '\n': out += "\\n"; break;
        case '\t': out += "\\t"; break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof(buf), "\\u%04x", c);
            out += buf;
          } else {
            out += c;
          }
      }
    }
    return out + "\"";
  }

 private:
  JsonWriter& Open(char c) {
    Separator();
    os_ << c;
    first_.push_back(true);
    return *this;
  }
  JsonWriter& Close(char c) {
    const bool empty = first_.back();
    first_.pop_back();
    if (!empty) os_ << "\n" << std::string(2 * first_.size(), ' ');
    os_ << c;
    return *this;
  }
  JsonWriter& Raw(const std::string& text) {
    Separator();
    os_ << text;
    return *this;
  }
  void Separator() {
    if (after_key_) {
      after_key_ = false;
      return;
    }
    if (first_.empty()) return;
    if (!first_.back()) os_ << ",";
    os_ << "\n" << std::string(2 * first_.size(), ' ');
    first_.back() = false;
  }

  std::ostringstream os_;
  std::vector<bool> first_;
  bool after_key_ = false;
};

}  // namespace rover::tools
