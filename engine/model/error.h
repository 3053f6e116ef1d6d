// The one error type of the engine: the message names the item, its index and the bad value.
// The Python module maps it to ValueError.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace novaphy {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Error built from streamable parts: fail("body ", 3, ": mass must be positive, got ", m)
template <typename... Parts>
[[noreturn]] void fail(const Parts&... parts) {
  std::ostringstream os;
  os.precision(17);
  (os << ... << parts);
  throw Error(os.str());
}

}  // namespace novaphy
