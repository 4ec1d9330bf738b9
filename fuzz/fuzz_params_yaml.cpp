// params.yaml (calibrated parameters): any text ends as parameters or a DataError; anything
// else is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "polrig/io/measured.h"  // DataError
#include "polrig/io/params_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    polrig::parse_params_yaml(text, "fuzz/params.yaml");
  } catch (const polrig::DataError&) {
  }
  return 0;
}
