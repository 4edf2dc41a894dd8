// nlohmann::json::parse (parse errors are not findings) → model_from_json.
// A returned model must have consistent shapes and finite entries.
#include <nlohmann/json.hpp>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  try {
    const fdsid::StateSpace s = fdsid::model_from_json(j, "fuzz");
    fdsid_fuzz::check_model(s, "model_from_json");
  } catch (const fdsid::Error&) {
  }
  return 0;
}
