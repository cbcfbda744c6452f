// Private to the H² factorization: a block of the frontier's store.
#pragma once

#include "hssbem/core/dense_matrix.hpp"

#include <cstddef>
#include <vector>

namespace hssbem::h2f {

/// With single-precision storage (a loose tolerance) a block rests in single precision between
/// the steps that change it: open() widens it to double for a step, park() narrows it again. The
/// rounding (6e-8) lies far below such a tolerance, and the store (the near field in double at
/// the first level, the bulk of the factorization's workspace) halves.
class StoredBlock {
public:
  StoredBlock() = default;
  explicit StoredBlock(DenseMatrix B) : m_d(std::move(B)) {}
  int rows() const { return m_d.m; }
  int cols() const { return m_d.n; }
  DenseMatrix &open()
  {
    if (m_parked) {
      m_d.a.assign(m_s.begin(), m_s.end());
      std::vector<float>().swap(m_s);
      m_parked = false;
    }
    return m_d;
  }
  void park()
  {
    if (m_parked) return;
    m_s.assign(m_d.a.begin(), m_d.a.end());
    std::vector<double>().swap(m_d.a);
    m_parked = true;
  }
  /// A copy in double, parked or not.
  DenseMatrix value() const
  {
    if (!m_parked) return m_d;
    DenseMatrix out(m_d.m, m_d.n);
    std::copy(m_s.begin(), m_s.end(), out.a.begin());
    return out;
  }
  /// The block itself while it is open (in double), else null.
  const DenseMatrix *peek() const { return m_parked ? nullptr : &m_d; }
  /// The block in double, moved out (the stored block is left empty).
  DenseMatrix take()
  {
    DenseMatrix out = m_parked ? value() : std::move(m_d);
    *this = StoredBlock();
    return out;
  }
  std::size_t bytes() const { return m_d.bytes() + m_s.size() * sizeof(float); }

private:
  DenseMatrix m_d;        ///< sizes always; entries while open
  std::vector<float> m_s; ///< entries while parked
  bool m_parked = false;
};

} // namespace hssbem::h2f
