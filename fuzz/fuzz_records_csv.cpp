// parse_records_csv, then record_statistics with a RecordMeta made from the
// leading bytes:
//   byte 0: period P (0..64), byte 1: periods M (0..9), byte 2: number of
//   excited lines (0..7), byte 3: domain (bit 0) and sample time (bits 1..),
//   then one byte per excited line (0..P/2+1); the rest is the CSV.
#include <sstream>
#include <string>

#include "fdsid/error.hpp"
#include "fdsid/frf_id.hpp"
#include "fdsid/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  fdsid::RecordMeta meta;
  meta.period = data[0] % 65;
  meta.periods = data[1] % 10;
  const int lines = data[2] % 8;
  const fdsid::Domain domain = (data[3] & 1u) ? fdsid::Domain::Continuous : fdsid::Domain::Discrete;
  static const double ts[] = {1.0, 0.5, 1e-3, 0.0, -1.0, 1e300, 1e-300};
  meta.sample_time = ts[(data[3] >> 1) % (sizeof ts / sizeof ts[0])];
  size_t pos = 4;
  for (int l = 0; l < lines && pos < size; ++l, ++pos) meta.excited_lines.push_back(data[pos] % (meta.period / 2 + 2));

  std::istringstream in(std::string(reinterpret_cast<const char*>(data + pos), size - pos));
  Eigen::MatrixXd samples;
  int inputs = -1;
  try {
    samples = fdsid::parse_records_csv(in, "fuzz.csv", inputs);
  } catch (const fdsid::Error&) {
    return 0;
  }
  if (inputs < 1 || inputs >= samples.cols()) fdsid_fuzz::fail("records: bad number of inputs accepted");
  if (samples.rows() < 1) fdsid_fuzz::fail("records: no rows accepted");
  if (!fdsid_fuzz::finite(samples)) fdsid_fuzz::fail("records: non-finite sample accepted");
  try {
    const fdsid::SampleStatistics st = fdsid::record_statistics(samples, inputs, meta, domain);
    if (st.data.frequencies() != static_cast<int>(meta.excited_lines.size()))
      fdsid_fuzz::fail("records: statistics at the wrong number of lines");
  } catch (const fdsid::Error&) {
  }
  return 0;
}
