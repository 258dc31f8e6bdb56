// SPDX-License-Identifier: BSD-3-Clause
// compression/src/byte_io.h -- little-endian field (de)serialisation with bounds checks (private).
#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "huge_pages.h"
#include "penumbra/core/error.h"

namespace penumbra::compression::detail {

class ByteWriter {
public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : m_out(out) {}
  template <class T>
  void put(const T& value) {
    append(&value, sizeof(T));
  }
  template <class T>
  void put_array(const std::vector<T>& values) {
    append(values.data(), values.size() * sizeof(T));
  }
  void append(const void* data, std::size_t bytes) {
    if (bytes == 0) return;
    const std::size_t at = m_out.size();
    m_out.resize(at + bytes);
    std::memcpy(m_out.data() + at, data, bytes);
  }
  std::size_t size() const { return m_out.size(); }

private:
  std::vector<std::uint8_t>& m_out;
};

/// Reads fields from a byte range; running past the end throws Error(io_error) with `context`.
class ByteReader {
public:
  ByteReader(const std::uint8_t* data, std::size_t size, std::string context)
      : m_data(data), m_size(size), m_context(std::move(context)) {}
  template <class T>
  T get() {
    T value;
    take(&value, sizeof(T));
    return value;
  }
  template <class T>
  void get_array(std::vector<T>& out, std::uint64_t count, std::size_t padding_bytes = 0) {
    if (count > (m_size - m_pos) / sizeof(T)) fail("ends inside an array");
    const std::uint64_t size = count + (padding_bytes + sizeof(T) - 1) / sizeof(T);
    reserve_on_huge_pages(out, size);
    out.resize(size);
    take(out.data(), count * sizeof(T));
    if (padding_bytes) std::memset(reinterpret_cast<std::uint8_t*>(out.data()) + count * sizeof(T), 0, padding_bytes);
  }
  void take(void* out, std::size_t bytes) {
    if (bytes > m_size - m_pos) fail("ends early");
    if (bytes == 0) return;  // an empty table's data() may be null, which memcpy may not take
    std::memcpy(out, m_data + m_pos, bytes);
    m_pos += bytes;
  }
  std::size_t position() const { return m_pos; }
  std::size_t remaining() const { return m_size - m_pos; }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ErrorCode::io_error, m_context + ": " + what + " (at byte " + std::to_string(m_pos) + " of " +
                                         std::to_string(m_size) + ")");
  }

private:
  const std::uint8_t* m_data;
  std::size_t m_size;
  std::size_t m_pos = 0;
  std::string m_context;
};

}  // namespace penumbra::compression::detail
