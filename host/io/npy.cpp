// .npy reading (strict) and writing.
#include "io/npy.hpp"

#include <cstdint>
#include <cstring>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/file.hpp"

namespace mipnerf::io {
namespace {

constexpr std::string_view kMagic = "\x93NUMPY";

// The header's Python dict literal: {'descr': '<f8', 'fortran_order': False, 'shape': (20, 17), }
struct Header {
  std::string descr;
  bool fortran_order = false;
  std::vector<size_t> shape;
  bool has_descr = false, has_order = false, has_shape = false;
};

class HeaderParser {
 public:
  HeaderParser(std::string_view text, const std::string& where) : text_(text), where_(where) {}

  Header parse() {
    Header h;
    expect('{');
    while (!peek('}')) {
      const std::string key = quoted();
      expect(':');
      if (key == "descr") {
        h.descr = quoted();
        h.has_descr = true;
      } else if (key == "fortran_order") {
        h.fortran_order = boolean();
        h.has_order = true;
      } else if (key == "shape") {
        h.shape = tuple();
        h.has_shape = true;
      } else {
        fail("unknown key '" + key + "'");
      }
      if (!peek('}')) expect(',');
    }
    expect('}');
    skip_space();
    if (at_ != text_.size()) fail("text after the dict");
    if (!h.has_descr || !h.has_order || !h.has_shape) fail("it needs the keys 'descr', 'fortran_order' and 'shape'");
    return h;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(where_ + ": malformed .npy header (" + what + " at character " + std::to_string(at_) + ")");
  }
  void skip_space() {
    while (at_ < text_.size() && (text_[at_] == ' ' || text_[at_] == '\n' || text_[at_] == '\t')) ++at_;
  }
  bool peek(char c) {
    skip_space();
    return at_ < text_.size() && text_[at_] == c;
  }
  void expect(char c) {
    if (!peek(c)) fail(std::string("expected '") + c + "'");
    ++at_;
  }
  std::string quoted() {
    skip_space();
    if (at_ >= text_.size() || (text_[at_] != '\'' && text_[at_] != '"')) fail("expected a quoted string");
    const char quote = text_[at_++];
    const size_t end = text_.find(quote, at_);
    if (end == std::string_view::npos) fail("unterminated string");
    std::string value(text_.substr(at_, end - at_));
    at_ = end + 1;
    return value;
  }
  bool boolean() {
    skip_space();
    for (const auto& [word, value] : {std::pair<std::string_view, bool>{"True", true}, {"False", false}}) {
      if (text_.substr(at_, word.size()) == word) {
        at_ += word.size();
        return value;
      }
    }
    fail("expected True or False");
  }
  std::vector<size_t> tuple() {
    expect('(');
    std::vector<size_t> values;
    while (!peek(')')) {
      skip_space();
      size_t value = 0, digits = 0;
      while (at_ < text_.size() && text_[at_] >= '0' && text_[at_] <= '9') {
        if (++digits > 15) fail("a dimension too large");
        value = value * 10 + static_cast<size_t>(text_[at_++] - '0');
      }
      if (digits == 0) fail("expected a dimension");
      values.push_back(value);
      if (!peek(')')) expect(',');
    }
    expect(')');
    return values;
  }

  std::string_view text_;
  const std::string& where_;
  size_t at_ = 0;
};

// The unsigned little-endian integer of `count` bytes at `at` (the header length: 2 bytes in version 1, 4 after).
uint64_t little_endian_at(std::string_view bytes, size_t at, int count) {
  uint64_t v = 0;
  for (int i = 0; i < count; ++i) v |= static_cast<uint64_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
  return v;
}

}  // namespace

NpyArray parse_npy(std::string_view bytes, const std::string& where) {
  if (bytes.substr(0, kMagic.size()) != kMagic) throw Error(where + ": not a .npy file (it does not start with \\x93NUMPY)");
  if (bytes.size() < kMagic.size() + 4) throw Error(where + ": truncated .npy file");
  const int major = static_cast<unsigned char>(bytes[6]);
  if (major < 1 || major > 3) throw Error(where + ": .npy format version " + std::to_string(major) + " (expected 1 to 3)");
  const int length_bytes = major == 1 ? 2 : 4;
  const size_t header_start = 8 + static_cast<size_t>(length_bytes);
  if (bytes.size() < header_start) throw Error(where + ": truncated .npy file");
  const uint64_t header_length = little_endian_at(bytes, 8, length_bytes);
  if (header_length > bytes.size() - header_start) throw Error(where + ": truncated .npy header");
  const Header header = HeaderParser(bytes.substr(header_start, header_length), where).parse();
  if (header.fortran_order) throw Error(where + ": a Fortran-order array; save it in C order (numpy's default)");
  size_t item_bytes = 0;
  if (header.descr == "<f8") item_bytes = 8;
  else if (header.descr == "<f4") item_bytes = 4;
  else throw Error(where + ": dtype '" + header.descr + "'; expected little-endian float64 '<f8' or float32 '<f4'");

  const size_t data_start = header_start + header_length;
  const size_t data_bytes = bytes.size() - data_start;
  size_t count = 1;
  for (size_t d : header.shape) {
    if (d != 0 && count > data_bytes / item_bytes / d) {
      throw Error(where + ": its shape needs more data than the file's " + std::to_string(data_bytes) + " bytes");
    }
    count *= d;
  }
  if (count * item_bytes != data_bytes) {
    throw Error(where + ": " + std::to_string(data_bytes) + " bytes of data where its shape needs " +
                std::to_string(count * item_bytes));
  }
  NpyArray array;
  array.shape = header.shape;
  array.values.resize(count);
  const char* data = bytes.data() + data_start;
  for (size_t i = 0; i < count; ++i) {
    if (item_bytes == 8) {
      std::memcpy(&array.values[i], data + 8 * i, 8);  // little-endian hosts only, as the checkpoints
    } else {
      float f;
      std::memcpy(&f, data + 4 * i, 4);
      array.values[i] = f;
    }
  }
  return array;
}

NpyArray read_npy(const std::string& path) {
  const std::string bytes = read_file_text(path);
  return parse_npy(bytes, path);
}

std::string npy_bytes(const std::vector<double>& values, const std::vector<size_t>& shape) {
  std::string dims;
  for (size_t d : shape) dims += std::to_string(d) + ", ";
  if (shape.size() > 1) dims.resize(dims.size() - 2);  // "(20, 17)"; a 1-d shape keeps its comma: "(5,)"
  else if (!dims.empty()) dims.resize(dims.size() - 1);
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + dims + "), }";
  // Padded with spaces and a newline so the data starts on a 64-byte boundary, as numpy writes it.
  const size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header += '\n';
  std::string bytes(kMagic);
  bytes += '\x01';
  bytes += '\x00';
  bytes += static_cast<char>(header.size() & 0xff);
  bytes += static_cast<char>((header.size() >> 8) & 0xff);
  bytes += header;
  bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
  return bytes;
}

void write_npy(const std::string& path, const std::vector<double>& values, const std::vector<size_t>& shape) {
  write_bytes_atomically(path, npy_bytes(values, shape));
}

}  // namespace mipnerf::io
