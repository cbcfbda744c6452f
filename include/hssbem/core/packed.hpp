/// \file packed.hpp
/// A stored form packed into three streams (doubles, floats, integers), and read back with every
/// length checked: how a precomputation made of many small arrays (an H² matrix's blocks, an H²
/// factorization's steps) is saved as three large arrays (session/h2_file.hpp) instead of
/// thousands of small ones. The reader never reads past a stream's end and refuses a negative or
/// oversized length (std::invalid_argument "damaged: ..."), so a damaged stream is one error,
/// never a crash.
#pragma once

#include "hssbem/core/dense_matrix.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

/// The three streams.
struct PackedArrays {
  std::vector<double> d;
  std::vector<float> f;
  std::vector<int> i;
};

/// Appends to a PackedArrays; each array goes with its length (in the integer stream).
class PackWriter {
public:
  explicit PackWriter(PackedArrays &out) : m_out(out) {}
  void put(int v) { m_out.i.push_back(v); }
  void put(double v) { m_out.d.push_back(v); }
  void put(const std::vector<int> &v) { put_array(m_out.i, v.data(), v.size()); }
  void put(const std::vector<double> &v) { put_array(m_out.d, v.data(), v.size()); }
  void put(const std::vector<float> &v) { put_array(m_out.f, v.data(), v.size()); }
  /// The sizes, then the entries (column-major, m × n of them, or none when the matrix holds none).
  void put(const DenseMatrix &M)
  {
    put(M.m), put(M.n);
    put(M.a);
  }

private:
  template <class T> void put_array(std::vector<T> &to, const T *v, std::size_t n)
  {
    if (n > static_cast<std::size_t>(INT32_MAX)) throw std::length_error("packed array longer than 2^31 entries");
    put(static_cast<int>(n));
    to.insert(to.end(), v, v + n);
  }
  PackedArrays &m_out;
};

/// Reads what PackWriter wrote, in the same order. Throws std::invalid_argument("damaged: <what>")
/// when a stream ends early or a length or size is impossible.
class PackReader {
public:
  explicit PackReader(const PackedArrays &in) : m_in(in) {}
  int get_int()
  {
    need(m_in.i.size(), m_i, 1, "integers");
    return m_in.i[m_i++];
  }
  /// An integer in [lo, hi].
  int get_int(int lo, int hi, const char *what)
  {
    const int v = get_int();
    if (v < lo || v > hi) throw std::invalid_argument(std::string("damaged: ") + what + " " + std::to_string(v) + " out of range");
    return v;
  }
  double get_double()
  {
    need(m_in.d.size(), m_d, 1, "doubles");
    return m_in.d[m_d++];
  }
  void get(std::vector<int> &v) { get_array(m_in.i, m_i, v, "integers"); }
  void get(std::vector<double> &v) { get_array(m_in.d, m_d, v, "doubles"); }
  void get(std::vector<float> &v) { get_array(m_in.f, m_f, v, "floats"); }
  void get(DenseMatrix &M)
  {
    M.m = get_int(0, INT32_MAX, "matrix rows");
    M.n = get_int(0, INT32_MAX, "matrix columns");
    get(M.a);
    if (!M.a.empty() && M.a.size() != static_cast<std::size_t>(M.m) * M.n) throw std::invalid_argument("damaged: a matrix's entries do not fit its sizes");
  }
  /// Whether every stream was read to its end.
  bool done() const { return m_i == m_in.i.size() && m_d == m_in.d.size() && m_f == m_in.f.size(); }

private:
  static void need(std::size_t size, std::size_t at, std::size_t n, const char *what)
  {
    if (n > size - at) throw std::invalid_argument(std::string("damaged: the ") + what + " end early");
  }
  template <class T> void get_array(const std::vector<T> &from, std::size_t &at, std::vector<T> &v, const char *what)
  {
    const std::size_t n = static_cast<std::size_t>(get_int(0, INT32_MAX, "array length"));
    need(from.size(), at, n, what);
    v.assign(from.begin() + static_cast<std::ptrdiff_t>(at), from.begin() + static_cast<std::ptrdiff_t>(at + n));
    at += n;
  }
  const PackedArrays &m_in;
  std::size_t m_i = 0, m_d = 0, m_f = 0;
};

} // namespace hssbem
