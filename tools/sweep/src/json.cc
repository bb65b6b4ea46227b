#include "json.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vio::tools {
namespace {

class JsonParser {
 public:
  JsonParser(const std::string& text, const std::string& origin) : text_(text), origin_(origin) {}

  JsonValue Document() {
    JsonValue value = Value();
    SkipBlanks();
    if (pos_ != text_.size()) Fail("text after the JSON value");
    return value;
  }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    throw std::runtime_error(origin_ + ": offset " + std::to_string(pos_) + ": malformed JSON: " + what);
  }

  void SkipBlanks() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\n' || text_[pos_] == '\r' ||
                                   text_[pos_] == '\t')) {
      ++pos_;
    }
  }

  char Peek() {
    SkipBlanks();
    if (pos_ >= text_.size()) Fail("unexpected end");
    return text_[pos_];
  }

  void Expect(char c) {
    if (Peek() != c) Fail(std::string("expected '") + c + "'");
    ++pos_;
  }

  bool Literal(const std::string& word) {
    if (text_.compare(pos_, word.size(), word) != 0) return false;
    pos_ += word.size();
    return true;
  }

  JsonValue Value() {
    const char c = Peek();
    if (c == '{') return Object();
    if (c == '[') return Array();
    JsonValue v;
    if (c == '"') {
      v.type = JsonValue::Type::kString;
      v.string = String();
    } else if (Literal("null")) {
      v.type = JsonValue::Type::kNull;
    } else if (Literal("true")) {
      v.type = JsonValue::Type::kBool;
      v.boolean = true;
    } else if (Literal("false")) {
      v.type = JsonValue::Type::kBool;
    } else {
      v.type = JsonValue::Type::kNumber;
      v.number = Number();
    }
    return v;
  }

  double Number() {
    double value = 0.0;
    const char* begin = text_.data() + pos_;
    const auto [end, ec] = std::from_chars(begin, text_.data() + text_.size(), value);
    if (ec != std::errc() || end == begin) Fail("expected a value");
    pos_ += static_cast<size_t>(end - begin);
    return value;
  }

  std::string String() {
    Expect('"');
    std::string out;
    while (pos_ < text_.size() && text_[pos_] != '"') {
      char c = text_[pos_++];
      if (c == '\\') {
        if (pos_ >= text_.size()) Fail("unterminated string");
        const char e = text_[pos_++];
        c = e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e;
        if (e == 'u') Fail("\\u escapes are not supported");
      }
      out += c;
    }
    if (pos_ >= text_.size()) Fail("unterminated string");
    ++pos_;
    return out;
  }

  JsonValue Array() {
    JsonValue v;
    v.type = JsonValue::Type::kArray;
    Expect('[');
    if (Peek() == ']') {
      ++pos_;
      return v;
    }
    for (;;) {
      v.items.push_back(Value());
      if (Peek() != ',') break;
      ++pos_;
    }
    Expect(']');
    return v;
  }

  JsonValue Object() {
    JsonValue v;
    v.type = JsonValue::Type::kObject;
    Expect('{');
    if (Peek() == '}') {
      ++pos_;
      return v;
    }
    for (;;) {
      if (Peek() != '"') Fail("expected a key");
      v.keys.push_back(String());
      Expect(':');
      v.items.push_back(Value());
      if (Peek() != ',') break;
      ++pos_;
    }
    Expect('}');
    return v;
  }

  const std::string& text_;
  const std::string& origin_;
  size_t pos_ = 0;
};

}  // namespace

const JsonValue* JsonValue::Find(const std::string& key) const {
  if (type != Type::kObject) return nullptr;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (keys[i] == key) return &items[i];
  }
  return nullptr;
}

double JsonValue::AsNumber() const {
  if (type == Type::kNull) return std::numeric_limits<double>::quiet_NaN();
  if (type != Type::kNumber) throw std::runtime_error("JSON value is not a number");
  return number;
}

JsonValue ParseJson(const std::string& text, const std::string& origin) {
  return JsonParser(text, origin).Document();
}

}  // namespace vio::tools
