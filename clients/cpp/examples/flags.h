// Command-line flags of the example programs: one refusal type and one
// number parser, so every example says the same thing about a bad value.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace sim4cv::examples {

// A bad command line; the program prints the message and its usage.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// `text` as a whole number (int) or a number (double) in [min, max], else a
// UsageError naming the flag, the range and the text.
template <typename Number>
Number ParseNumber(const std::string& flag, const std::string& text, Number min, Number max) {
  static_assert(std::is_same_v<Number, int> || std::is_same_v<Number, double>, "int or double");
  std::size_t used = 0;
  Number value{};
  try {
    if constexpr (std::is_same_v<Number, int>) {
      value = std::stoi(text, &used);
    } else {
      value = std::stod(text, &used);
    }
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(value >= min && value <= max)) {
    std::ostringstream message;  // 0.1, not 0.100000
    message << flag << " wants " << (std::is_same_v<Number, int> ? "an integer" : "a number") << " in [" << min << ", "
            << max << "], got '" << text << "'";
    throw UsageError(message.str());
  }
  return value;
}

}  // namespace sim4cv::examples
