// nlohmann::json::parse (parse errors are not findings) → meta_from_json.
#include <cmath>

#include <nlohmann/json.hpp>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  try {
    const fdsid::RecordMeta m = fdsid::meta_from_json(j, "fuzz");
    if (!std::isfinite(m.sample_time)) fdsid_fuzz::fail("meta: non-finite sample_time accepted");
  } catch (const fdsid::Error&) {
  }
  return 0;
}
