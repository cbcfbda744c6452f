/// \file h5_handle.hpp
/// Private to io/: owners of HDF5 identifiers and of HDF5's error printing, with no MPI (the
/// saved-file reader and its fuzzer use them without the result writers).
#pragma once

#include <hdf5.h>

#include <string>
#include <utility>

namespace hssbem::detail {

/// Turns off HDF5's automatic error-stack printing while a writer runs: failures are reported
/// through OutputError instead, and the previous handler is restored afterwards.
class H5ErrorSilencer {
public:
  H5ErrorSilencer()
  {
    m_saved = H5Eget_auto2(H5E_DEFAULT, &m_func, &m_data) >= 0;
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  H5ErrorSilencer(const H5ErrorSilencer &) = delete;
  H5ErrorSilencer &operator=(const H5ErrorSilencer &) = delete;
  ~H5ErrorSilencer()
  {
    if (m_saved)
      H5Eset_auto2(H5E_DEFAULT, m_func, m_data);
  }

private:
  H5E_auto2_t m_func = nullptr;
  void *m_data = nullptr;
  bool m_saved = false;
};

/// Owns one HDF5 identifier, so error paths close everything they opened.
class H5Handle {
public:
  using Closer = herr_t (*)(hid_t);
  H5Handle(hid_t id, Closer closer) : m_id(id), m_closer(closer) {}
  H5Handle(const H5Handle &) = delete;
  H5Handle &operator=(const H5Handle &) = delete;
  ~H5Handle()
  {
    if (m_id >= 0)
      m_closer(m_id); // only reached on error paths, where a failed close changes nothing
  }
  hid_t get() const { return m_id; }
  /// Closes now and reports the status, for the success path where it matters.
  herr_t close() { return m_closer(std::exchange(m_id, H5I_INVALID_HID)); }
  /// Gives the identifier up, unclosed, to the caller.
  hid_t release() { return std::exchange(m_id, H5I_INVALID_HID); }

private:
  hid_t m_id;
  Closer m_closer;
};

/// The innermost message of HDF5's error stack (e.g. the errno text of a failed open). Must run
/// before the next HDF5 call, which clears the stack.
inline std::string h5_reason()
{
  std::string reason;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t *err, void *out) -> herr_t {
        if (n == 0 && err->desc) // walking upward, entry 0 is where the error was detected
          *static_cast<std::string *>(out) = err->desc;
        return 0;
      },
      &reason);
  return reason;
}

} // namespace hssbem::detail
