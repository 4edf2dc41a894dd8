#include "fdsid/io.hpp"

#include <algorithm>
#include <array>
#include <functional>
#include <iterator>
#include <new>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <type_traits>
#include <set>
#include <sstream>
#include <vector>

#include <unistd.h>

#include "fdsid/error.hpp"
#include "fdsid/format.hpp"

namespace fdsid {

namespace {

[[noreturn]] void input_error(const std::string& where, const std::string& what) {
  throw Error(ErrorKind::Input, where, what);
}

// A number of the file formats: [+|-]digits[.digits][(e|E)[+|-]digits], in
// the C locale. std::from_chars (general format) takes exactly that (no
// hexadecimal "0x10", no spaces, no decimal comma — strtod took "0x10" as 16)
// plus inf/nan, which the finiteness test refuses. A magnitude beyond the
// double range is named as an overflow, one below it is read as strtod reads
// it (0 or a subnormal).
double parse_decimal(const std::string& text, const std::string& where) {
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') ++b;
  double x = 0;
  const auto [end, ec] = std::from_chars(b, e, x, std::chars_format::general);
  if (text.empty() || end != e || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
    std::string hint;
    if (text.find(',') != std::string::npos) hint = " (a decimal comma? write 0.5, not 0,5)";
    else if (text.find("0x") != std::string::npos || text.find("0X") != std::string::npos)
      hint = " (hexadecimal is not data)";
    input_error(where, "\"" + text + "\" is not a decimal number" + hint);
  }
  if (ec == std::errc::result_out_of_range) {
    x = std::strtod(text.c_str(), nullptr);
    if (std::abs(x) > 1.0) input_error(where, "\"" + text + "\" overflows a double (beyond ±1.8e308)");
  }
  if (!std::isfinite(x)) input_error(where, "\"" + text + "\" is not finite (NaN and Inf are not data)");
  return x;
}

double number_from_json(const nlohmann::json& v, const std::string& where) {
  if (v.is_number()) {
    const double x = v.get<double>();
    if (!std::isfinite(x)) input_error(where, "not a finite number");
    return x;
  }
  if (v.is_string()) return parse_decimal(v.get<std::string>(), where);
  input_error(where, "expected a number or a decimal string, got " + std::string(v.type_name()));
}

Eigen::MatrixXd matrix_from_json(const nlohmann::json& j, const std::string& key, const std::string& where) {
  if (!j.contains(key)) input_error(where, "field \"" + key + "\" is missing");
  const auto& v = j.at(key);
  const std::string w = where + " field \"" + key + "\"";
  if (!v.is_array()) input_error(w, "must be an array of rows");
  const auto rows = v.size();
  if (rows == 0) return Eigen::MatrixXd(0, 0);
  if (!v[0].is_array()) input_error(w, "must be an array of rows (arrays)");
  const auto cols = v[0].size();
  Eigen::MatrixXd M(rows, cols);
  for (size_t i = 0; i < rows; ++i) {
    if (!v[i].is_array() || v[i].size() != cols)  // both rows named: row 1 may be the short one
      input_error(w, "row " + std::to_string(i + 1) + " has " +
                         (v[i].is_array() ? std::to_string(v[i].size()) : std::string("no")) + " entries, row 1 has " +
                         std::to_string(cols) + ": the rows of a matrix have one length");
    for (size_t c = 0; c < cols; ++c)
      M(i, c) = number_from_json(v[i][c], w + "[" + std::to_string(i) + "][" + std::to_string(c) + "]");
  }
  return M;
}

nlohmann::json matrix_to_json(const Eigen::MatrixXd& M) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < M.cols(); ++c) row.push_back(M(i, c));
    a.push_back(row);
  }
  return a;
}

// Cells of one CSV line: split at commas, spaces and a CR trimmed, one pair
// of enclosing double quotes removed ("u","y": the benchmark files' style).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream s(line);
  while (std::getline(s, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    size_t b = 0;
    while (b < cell.size() && cell[b] == ' ') ++b;
    cell = cell.substr(b);
    if (cell.size() >= 2 && cell.front() == '"' && cell.back() == '"') cell = cell.substr(1, cell.size() - 2);
    out.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();  // "a,b,\r" already ends in the empty cell "\r"
  return out;
}

// The header row of a CSV file, read as the files come (review finding 19):
// a UTF-8 byte-order mark is skipped, a trailing comma (every file in
// ../shared/data has one) is dropped here and on every row; a semicolon or
// tab separator and a missing header row are named as such.
struct CsvHeader {
  std::vector<std::string> cells;
  bool trailing_comma = false;
};

CsvHeader read_csv_header(std::istream& in, const std::string& name, const std::string& expected) {
  std::string line;
  if (!std::getline(in, line)) input_error(name, "empty file (expected a header " + expected + ")");
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
  if (line.find(',') == std::string::npos) {
    const size_t semi = line.find(';'), tab = line.find('\t');
    if (semi != std::string::npos || tab != std::string::npos)
      input_error(name + " line 1", std::string("the separator is ") + (semi != std::string::npos ? "';'" : "a tab") +
                                        ": fdsid reads comma-separated files with a decimal point (expected " +
                                        expected + ")");
  }
  CsvHeader h;
  h.cells = split_csv(line);
  if (h.cells.size() > 1 && h.cells.back().empty()) {
    h.trailing_comma = true;
    h.cells.pop_back();
  }
  if (!h.cells.empty()) {
    char* end = nullptr;
    const std::string& c0 = h.cells[0];
    std::strtod(c0.c_str(), &end);
    if (!c0.empty() && end == c0.c_str() + c0.size())
      input_error(name + " line 1", "holds numbers, not the header row: add the header " + expected + " as line 1");
  }
  return h;
}

double parse_cell(const std::string& cell, const std::string& where) {
  if (cell.empty()) input_error(where, "empty value");
  return parse_decimal(cell, where);
}

// The data rows after the header: blank lines skipped, every row split and
// checked to have the header's `cols` fields, then handed with its place
// ("NAME line K", lines counted 1-based from the header) to `row`.
template <class Row>
void for_each_csv_row(std::istream& in, const std::string& name, const CsvHeader& header, Row&& row) {
  const size_t cols = header.cells.size();
  std::string line;
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    auto cells = split_csv(line);
    if (header.trailing_comma && cells.size() == cols + 1 && cells.back().empty()) cells.pop_back();
    const std::string where = name + " line " + std::to_string(lineno);
    if (cells.size() != cols)
      input_error(where, "has " + std::to_string(cells.size()) + " fields, the header has " + std::to_string(cols) +
                             (cells.size() > cols ? " (a decimal comma? write 0.5, not 0,5)" : ""));
    if constexpr (std::is_invocable_v<Row, const std::vector<std::string>&, const std::string&, int>)
      row(cells, where, lineno);
    else
      row(cells, where);
  }
}

}  // namespace

StateSpace model_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) input_error(where, "expected a JSON object");
  StateSpace m;
  // Both fields are part of the model (the contracts' model format): a model
  // without them used to be taken silently as discrete with Ts = 1, and a
  // continuous-time model without "domain" then as an unstable discrete one.
  const std::string domains = name_list(domain_names(), "\"");
  if (!j.contains("domain")) input_error(where + " field \"domain\"", "is missing: add \"domain\": " + domains);
  if (!j["domain"].is_string()) input_error(where + " field \"domain\"", "must be " + domains);
  const std::string d = j["domain"];
  const std::optional<Domain> domain = from_name(domain_names(), d);
  if (!domain) input_error(where + " field \"domain\"", "\"" + d + "\" is not " + domains);
  m.domain = *domain;
  if (j.contains("sample_time")) m.sample_time = number_from_json(j["sample_time"], where + " field \"sample_time\"");
  else if (m.domain == Domain::Discrete)
    input_error(where + " field \"sample_time\"",
                "is missing: a discrete-time model needs its sample time in seconds (1.0 when time is counted in samples)");
  m.A = matrix_from_json(j, "A", where);
  m.B = matrix_from_json(j, "B", where);
  m.C = matrix_from_json(j, "C", where);
  m.D = matrix_from_json(j, "D", where);
  // An order-0 model has empty A: give B and C the shapes D implies.
  if (m.A.size() == 0) {
    m.B.resize(0, m.D.cols());
    m.C.resize(m.D.rows(), 0);
  }
  validate(m, where);
  // fdsid writes the order beside A; a file whose "order" disagrees with A
  // was edited by hand or written by a tool that mixed two models (a user
  // review: "order": 3 on a 4-state A was accepted silently).
  if (j.contains("order")) {
    const nlohmann::json& o = j["order"];
    const std::string rows = std::to_string(m.A.rows());
    if (!o.is_number_integer())
      input_error(where + " field \"order\"", "is " + o.dump() + ", not a whole number (the size of A: " + rows + ")");
    if (o.get<long long>() != m.A.rows())
      input_error(where + " field \"order\"",
                  "is " + o.dump() + " but A has " + rows + " rows: the order is the size of A; correct \"order\" or remove it");
  }
  return m;
}

namespace {
void check_readable_file(const std::string& path, const char* what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) input_error(path, std::string("is a directory, not a ") + what);
  // A CSV cell of ~10 bytes becomes an 8-byte double held in a growing vector
  // (up to 2x while it grows), then copied once into a matrix.
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) require_memory(3.0 * double(size), path, std::string("reading this ") + what);
}

nlohmann::json read_json_file(const std::string& path, const char* what) {
  check_readable_file(path, what);
  std::ifstream f(path);
  if (!f) input_error(path, std::string("cannot open ") + what + " (" + std::strerror(errno) + ")");
  // A key given twice in one object was taken silently, the last one winning
  // (review finding 12): the parser callback keeps the keys of every open object.
  std::vector<std::set<std::string>> keys;
  const auto no_duplicates = [&](int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (event == E::object_start) keys.emplace_back();
    else if (event == E::object_end && !keys.empty()) keys.pop_back();
    else if (event == E::key && !keys.empty() && !keys.back().insert(parsed.get<std::string>()).second)
      input_error(path, "key \"" + parsed.get<std::string>() + "\" appears twice in one object");
    return true;
  };
  try {
    return nlohmann::json::parse(f, no_duplicates);
  } catch (const nlohmann::json::parse_error& e) {
    input_error(path, std::string("malformed JSON: ") + e.what());
  }
}
}  // namespace

nlohmann::json read_model_file(const std::string& path) { return read_json_file(path, "model file"); }

StateSpace read_model(const std::string& path) { return model_from_json(read_model_file(path), path); }

nlohmann::json model_to_json(const StateSpace& m) {
  return {{"domain", to_string(m.domain)}, {"sample_time", m.sample_time}, {"A", matrix_to_json(m.A)},
          {"B", matrix_to_json(m.B)},       {"C", matrix_to_json(m.C)},       {"D", matrix_to_json(m.D)}};
}

nlohmann::json poles_to_json(const StateSpace& model) {
  nlohmann::json out = nlohmann::json::array();
  for (const cplx& z : poles(model)) out.push_back({z.real(), z.imag()});
  return out;
}

nlohmann::json result_to_json(const SpectrumResult& r) {
  nlohmann::json j = model_to_json(r.model);
  j["order"] = r.order;
  j["method"] = to_string(r.method);
  j["p"] = r.p;
  j["r"] = r.r;
  j["N"] = r.N;
  j["extension"] = to_string(r.extension);
  j["singular_values"] = std::vector<double>(r.singular_values.data(), r.singular_values.data() + r.singular_values.size());
  j["singular_values_of"] = r.method == Method::Akcay2011 ? "Y (Akcay 2011 Eq. 19)" : "G_p F_r (Akcay 2011 Eq. 13)";
  j["order_selection"] = {{"from_data", r.order_from_data},
                          {"gap", {{"index", r.gap_index}, {"ratio", r.gap_ratio}}},
                          {"rule", "n maximising sigma_{2n}/sigma_{2n+1}"}};
  j["poles"] = poles_to_json(r.model);
  j["summands"] = {{"E", matrix_to_json(r.summands.E)}, {"F", matrix_to_json(r.summands.F)},
                   {"P", matrix_to_json(r.summands.P)}};
  j["diagnostics"] = {{"split_margin", r.split_margin},
                      {"min_spectrum_on_grid", r.min_spectrum},
                      {"max_zero_modulus", r.max_zero_modulus},
                      {"riccati_method", r.riccati_method},
                      {"riccati_iterations", r.riccati_iterations},
                      {"riccati_residual", r.riccati_residual},
                      {"error_estimate", r.error_estimate},
                      {"usable", usable_precision(r.error_estimate)}};
  j["warnings"] = r.warnings;
  return j;
}

namespace {
// The diagonal is real for a Hermitian S, but Akcay's (2011) Section 4 noise is
// complex, so noisy diagonal samples carry an imaginary part by design; that
// part is zero-mean and symmetric, and the default extension discards it. What
// noise does not do is keep one sign at every sample: for independent noise
// symmetric about 0, P(all N signs alike) = 2^(1−N), below 1e-11 at the
// N >= 40 samples this test waits for (a sign test, exact for any symmetric
// law). So a diagonal whose imaginary part has one sign at all N samples,
// each above the printing floor 1e-5 |S_aa(k)| (rounding alone never trips
// it), is refused: a cross-spectrum, or columns shifted, not an auto-spectrum.
void check_real_diagonal(const SpectrumData& d, const std::string& name) {
  if (d.M + 1 < 40) return;
  for (int a = 0; a < d.m; ++a) {
    int positive = 0, negative = 0;
    for (int k = 0; k <= d.M; ++k) {
      const cplx v = d.at(a, a, k);
      if (std::abs(v.imag()) <= 1e-5 * std::abs(v)) continue;
      (v.imag() > 0 ? positive : negative) += 1;
    }
    if (std::max(positive, negative) == d.M + 1) {
      const std::string col = d.m == 1 ? "S_im" : "S" + std::to_string(a + 1) + std::to_string(a + 1) + "_im";
      input_error(name + " column " + col,
                  "the imaginary part of a diagonal entry has one sign at all " + std::to_string(d.M + 1) +
                      " samples (each above 1e-5 of the entry): the diagonal of a power spectrum is real, and noise "
                      "would change sign (p = 2^(1-N) for symmetric noise); give an auto-spectrum (" + col +
                      " zero or noise), not a cross-spectrum, and check the column order");
    }
  }
}

// A power spectrum is Hermitian, S_ba = conj(S_ab), at every sample (a
// cross-spectrum estimate from data is so by construction); with the sign of
// one _im column flipped the algorithm would still run and return twice the
// order. Tolerance: a writer printing d >= 6 significant digits (C's %g, the
// fewest any common tool prints) rounds each entry by <= 0.5e-5 of itself, and
// |S_ab| <= sqrt(S_aa S_bb) for a positive semi-definite S (Cauchy-Schwarz),
// so two entries equal before printing differ by <= 1e-5 sqrt(|S_aa| |S_bb|).
void check_hermitian(const SpectrumData& d, const std::string& name) {
  check_real_diagonal(d, name);
  for (int k = 0; k <= d.M; ++k)
    for (int a = 0; a < d.m; ++a)
      for (int b = a + 1; b < d.m; ++b) {
        const double scale = std::sqrt(std::abs(d.at(a, a, k)) * std::abs(d.at(b, b, k)));
        const double dev = std::abs(d.at(b, a, k) - std::conj(d.at(a, b, k)));
        if (dev > 1e-5 * scale) {
          const std::string ab = std::to_string(a + 1) + std::to_string(b + 1);
          const std::string ba = std::to_string(b + 1) + std::to_string(a + 1);
          input_error(name + " line " + std::to_string(k + 2),
                      "S" + ba + " is not conj(S" + ab + ") (|S" + ba + " - conj(S" + ab + ")| = " + sci(dev) +
                          ", above 1e-5 sqrt(|S" + std::to_string(a + 1) + std::to_string(a + 1) + " S" +
                          std::to_string(b + 1) + std::to_string(b + 1) + "|) = " + sci(1e-5 * scale) +
                          "): a power spectrum is Hermitian; check the signs of the _im columns");
        }
      }
}
}  // namespace

SpectrumData parse_spectrum_csv(std::istream& in, const std::string& name) {
  const CsvHeader csv = read_csv_header(in, name, "omega,S_re,S_im[,S_var]");
  const auto& header = csv.cells;
  // An optional last column S_var: the variance of each sample's noise (spectrum_id.hpp).
  const bool has_var = !header.empty() && header.back() == "S_var";
  const auto cols = header.size() - (has_var ? 1 : 0);
  if (cols >= 3 && header[0] == "omega" && header[1] == "G_re")
    input_error(name + " line 1", "holds a frequency response (omega,G_re,G_im...), not a power spectrum: "
                                  "identify-frf --frf reads it");
  if (cols >= 2 && header[0] == "u")
    input_error(name + " line 1", "holds periodic records (u,y...), not a power spectrum: identify-frf --data reads them");
  if (cols < 3 || (cols - 1) % 2 != 0 || header[0] != "omega")
    input_error(name + " line 1", "header must be omega,S_re,S_im or omega,S11_re,S11_im,...,Smm_re,Smm_im (then optionally S_var)");
  const int entries = static_cast<int>((cols - 1) / 2);
  const int m = static_cast<int>(std::lround(std::sqrt(entries)));
  if (m * m != entries) input_error(name + " line 1", std::to_string(entries) + " complex columns is not m*m for any m");
  // Column names: S_re/S_im for m = 1, Sab_re/Sab_im row-major otherwise.
  for (int e = 0; e < entries; ++e) {
    const std::string base = m == 1 ? "S" : "S" + std::to_string(e / m + 1) + std::to_string(e % m + 1);
    if (header[1 + 2 * e] != base + "_re" || header[2 + 2 * e] != base + "_im")
      input_error(name + " line 1", "column " + std::to_string(2 + 2 * e) + " should be " + base + "_re then " + base +
                                        "_im, found " + header[1 + 2 * e] + "," + header[2 + 2 * e]);
  }
  std::vector<double> omega, variance;
  std::vector<cplx> values;
  for_each_csv_row(in, name, csv, [&](const std::vector<std::string>& cells, const std::string& where) {
    omega.push_back(parse_cell(cells[0], where + " column omega"));
    for (int e = 0; e < entries; ++e)
      values.emplace_back(parse_cell(cells[1 + 2 * e], where + " column " + header[1 + 2 * e]),
                          parse_cell(cells[2 + 2 * e], where + " column " + header[2 + 2 * e]));
    if (has_var) {
      const double v = parse_cell(cells[cols], where + " column S_var");
      if (!(v > 0)) input_error(where + " column S_var", "variance " + cells[cols] + " must be positive");
      variance.push_back(v);
    }
  });
  if (omega.size() < 2) input_error(name, "needs at least 2 samples (M >= 1), found " + std::to_string(omega.size()));
  SpectrumData d;
  d.m = m;
  d.M = static_cast<int>(omega.size()) - 1;
  // A uniform grid of step pi/M' that stops short of pi (its last rows lost)
  // is named as such, not as an off-grid line 3 (review finding 19); the
  // same 1e-9 pi as the grid test below.
  const double h = omega[1] - omega[0];
  const long M_h = h > 0 ? std::lround(M_PI / h) : 0;
  bool uniform = omega[0] == 0.0 && M_h > d.M && std::abs(M_PI / M_h - h) <= 1e-9 * M_PI;
  for (int k = 0; uniform && k <= d.M; ++k) uniform = std::abs(omega[k] - M_PI * k / M_h) <= 1e-9 * M_PI;
  if (uniform)
    throw Error(ErrorKind::Grid, name,
                "the " + std::to_string(d.M + 1) + " samples lie on the grid pi(k-1)/M of M = " + std::to_string(M_h) +
                    " but end at omega = " + fmt(omega[d.M], 6) + ", not pi: the last " +
                    std::to_string(M_h - d.M) + " row(s) are missing (the grid runs from 0 to pi, M+1 samples)");
  // The uniform-grid methods need omega_k = pi (k-1)/M exactly; ten significant
  // digits (relative 1e-9 of pi) is what a CSV writer printing %.10g keeps.
  for (int k = 0; k <= d.M; ++k) {
    const double expected = M_PI * k / d.M;
    if (std::abs(omega[k] - expected) > 1e-9 * M_PI)
      throw Error(ErrorKind::Grid, name + " line " + std::to_string(k + 2),
                  "omega = " + std::to_string(omega[k]) + " is not on the uniform grid pi(k-1)/M (expected " +
                      std::to_string(expected) + " for M = " + std::to_string(d.M) +
                      "): the uniform-grid methods need M+1 samples from 0 to pi");
  }
  d.S.resize(m * m, d.M + 1);
  if (has_var) d.variance = Eigen::Map<const Eigen::VectorXd>(variance.data(), d.M + 1);
  for (int k = 0; k <= d.M; ++k)
    for (int e = 0; e < entries; ++e) {
      const int a = e / m, b = e % m;  // CSV is row-major; S stores vec() column-major
      d.S(a + m * b, k) = values[static_cast<size_t>(k) * entries + e];
    }
  check_hermitian(d, name);
  return d;
}

SpectrumData read_spectrum_csv(const std::string& path) {
  check_readable_file(path, "spectrum file");
  std::ifstream f(path);
  if (!f) input_error(path, std::string("cannot open spectrum file (") + std::strerror(errno) + ")");
  return parse_spectrum_csv(f, path);
}

void write_spectrum_csv(std::ostream& out, const SpectrumData& d) {
  const int m = d.m;
  out << "omega";
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) {
      const std::string base = m == 1 ? "S" : "S" + std::to_string(a + 1) + std::to_string(b + 1);
      out << ',' << base << "_re," << base << "_im";
    }
  const bool has_var = d.variance.size() == d.M + 1;
  if (has_var) out << ",S_var";
  out << '\n';
  char buf[64];
  for (int k = 0; k <= d.M; ++k) {
    std::snprintf(buf, sizeof buf, "%.17g", M_PI * k / d.M);
    out << buf;
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) {
        const cplx v = d.at(a, b, k);
        std::snprintf(buf, sizeof buf, ",%.17g,%.17g", v.real(), v.imag());
        out << buf;
      }
    if (has_var) {
      std::snprintf(buf, sizeof buf, ",%.17g", d.variance(k));
      out << buf;
    }
    out << '\n';
  }
}

namespace {

// An FRF file written in cycles/sample (f/fs, as MATLAB's FrequencyUnit
// 'cycles/sample' or a DFT bin index over P) and read as rad/sample lies on
// [0, 1/2] inside [0, π], so the Nyquist check cannot see it (review finding
// 3 of stop 47: poles at 1/(2π) of the true frequencies, no word). Such a
// column is a DFT grid: every ω = k/P, P the period in samples, a power of two
// in the multisine records of the field (the F-16, Silverbox, circuit and tank
// sets all are). Refused when, with no unit given, all samples sit on k/P for
// a power of two P ≥ 4 with max ω ≤ 1/2; P is tried as j/d for the smallest
// spacing d and j = 1 … 8 (excited lines j bins apart). The test's tolerance,
// |ωP − k| ≤ 1e-9 max(1, k), admits a column printed to 10 or more
// significant digits (a shorter one is passed, not refused); a rad/sample DFT
// grid 2πk/P' meets it only if jP'/(2πd') lies within ~1e-9 of an integer,
// which for an irrational 2π no file size approaches. Decimal rad/sample
// grids (0.02 … 0.1 in 40 steps: k/780) are not powers of two and pass (two
// of the suite's narrow-band files are such); one on k/2^e below 1/2 is
// refused, and --frequency-unit rad reads it.
void refuse_cycles_per_sample_grid(const FrfData& d, const std::string& name) {
  const Eigen::Index F = d.omega.size();
  if (d.domain != Domain::Discrete || F < 3 || d.omega.maxCoeff() > 0.5) return;
  std::vector<double> w(d.omega.data(), d.omega.data() + F);
  std::sort(w.begin(), w.end());
  double spacing = 0;
  for (size_t i = 1; i < w.size(); ++i)
    if (w[i] > w[i - 1] && (spacing == 0 || w[i] - w[i - 1] < spacing)) spacing = w[i] - w[i - 1];
  if (!(spacing > 0)) return;
  for (int j = 1; j <= 8; ++j) {
    const double P = std::round(j / spacing);
    int e = 0;
    if (P < 4 || P > 0x1p30 || std::frexp(P, &e) != 0.5) continue;  // P = 2^(e−1) exactly
    const bool on_grid = std::all_of(w.begin(), w.end(), [P](double x) {
      const double k = std::round(x * P);
      return std::abs(x * P - k) <= 1e-9 * std::max(1.0, k);
    });
    if (!on_grid) continue;
    input_error(name + " column omega",
                "every omega is k/" + fmt(P, 10) + " and none exceeds " + fmt(w.back(), 6) +
                    " <= 1/2: cycles/sample (f/fs) rather than rad/sample? give --frequency-unit hz (with "
                    "--sample-time Ts for Hz), or --frequency-unit rad if the column is rad/sample");
  }
}

FrfData parse_frf(std::istream& in, const std::string& name, Domain domain, const FrequencyUnits& units,
                  size_t expected_rows = 0) {
  const double factor = units.factor(domain);
  const CsvHeader csv = read_csv_header(in, name, "omega,G_re,G_im[,G_var]");
  const auto& header = csv.cells;
  const bool has_var = header.size() == 4;
  if (!(header.size() == 3 || has_var) || header[0] != "omega" || header[1] != "G_re" || header[2] != "G_im" ||
      (has_var && header[3] != "G_var"))
    input_error(name + " line 1", "header must be omega,G_re,G_im or omega,G_re,G_im,G_var");
  std::vector<double> omega;
  ComplexMatrixStack G;
  RealMatrixStack var;
  // The file line of every row, for a repeated frequency, checked after the
  // rows (a map of omega -> line text held ~100 bytes per row: 10⁶ lines, a
  // third of identify-frf's peak memory).
  std::vector<int> lines;
  try {  // a hint only (blank lines count too): without it the vectors grow as before
    omega.reserve(expected_rows);
    G.reserve(static_cast<Eigen::Index>(expected_rows), 1, 1);
    if (has_var) var.reserve(static_cast<Eigen::Index>(expected_rows), 1, 1);
    lines.reserve(expected_rows);
  } catch (const std::bad_alloc&) {
  }
  for_each_csv_row(in, name, csv, [&](const std::vector<std::string>& cells, const std::string& where, int line) {
    const double column = parse_cell(cells[0], where + " column omega");
    const double w = column * factor;
    // Checked here, where the file line is known (review finding 21: the
    // library's check said "frequency 201 ... (data row k is file line k + 1)").
    if (domain == Domain::Discrete && (w < 0 || w > M_PI)) {
      if (units.is_default())
        input_error(where + " column omega", "omega = " + fmt(column, 6) +
                                                 " rad/sample is outside [0, pi] (Hz or rad/s? give --frequency-unit "
                                                 "and --sample-time, or --domain continuous)");
      input_error(where + " column omega",
                  "omega = " + fmt(column, 6) + " " + units.column_unit(domain) + " is " + fmt(w, 6) +
                      " rad/sample, outside [0, pi] (above the Nyquist frequency: is --sample-time right?)");
    }
    if (domain == Domain::Continuous && !(w > 0))
      input_error(where + " column omega", "omega = " + fmt(column, 6) + " " + units.column_unit(domain) +
                                               " must be positive for continuous time");
    lines.push_back(line);
    omega.push_back(w);
    G.push_back(Eigen::Matrix<cplx, 1, 1>(
        cplx(parse_cell(cells[1], where + " column G_re"), parse_cell(cells[2], where + " column G_im"))));
    if (has_var) {
      const double v = parse_cell(cells[3], where + " column G_var");
      if (!(v > 0)) input_error(where + " column G_var", "variance " + cells[3] + " must be positive");
      var.push_back(Eigen::Matrix<double, 1, 1>(v));
    }
  });
  if (omega.empty()) input_error(name, "no data rows");
  // The repeat a row-by-row check meets first. Increasing frequencies (the
  // usual file) repeat nothing; otherwise rows sorted by (omega, line): the
  // second row of each run of equal omegas repeats the run's first, and the
  // smallest such line is reported.
  if (std::adjacent_find(omega.begin(), omega.end(), std::greater_equal<double>()) != omega.end()) {
    std::vector<int> order(omega.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return omega[a] < omega[b]; });
    int repeat = -1, earlier = -1;
    for (size_t i = 1; i < order.size(); ++i) {
      const bool second_of_run = omega[order[i]] == omega[order[i - 1]] &&
                                 (i == 1 || omega[order[i - 1]] != omega[order[i - 2]]);
      if (second_of_run && (repeat < 0 || lines[order[i]] < lines[repeat])) {
        repeat = order[i];
        earlier = order[i - 1];
      }
    }
    if (repeat >= 0)
      input_error(name + " line " + std::to_string(lines[repeat]) + " column omega",
                  "omega = " + fmt(omega[repeat], 17) + " repeats " + name + " line " + std::to_string(lines[earlier]));
  }
  std::vector<int>().swap(lines);
  FrfData d = frf_data(domain, Eigen::Map<Eigen::VectorXd>(omega.data(), static_cast<Eigen::Index>(omega.size())),
                       std::move(G), std::move(var));
  if (domain == Domain::Discrete && units.sample_time > 0) d.sample_time = units.sample_time;
  validate(d, name);
  return d;
}

}  // namespace

double FrequencyUnits::factor(Domain domain) const {
  return (hz ? 2 * M_PI : 1.0) * (domain == Domain::Discrete && sample_time > 0 ? sample_time : 1.0);
}

std::string FrequencyUnits::column_unit(Domain domain) const {
  const bool per_second = domain == Domain::Continuous || sample_time > 0;
  return hz ? (per_second ? "Hz" : "cycles/sample") : (per_second ? "rad/s" : "rad/sample");
}

void require_frequency_units(const FrequencyUnits& units, Domain domain, bool from_frf) {
  if (units.is_default()) return;
  if (!from_frf)
    input_error("--frequency-unit/--sample-time",
                "apply to an FRF file (--frf); records carry their sample time in the meta");
  if (domain == Domain::Continuous && units.sample_time > 0)
    input_error("--sample-time",
                "applies to discrete-time FRFs; a continuous-time omega is already per second (drop it, or use "
                "--frequency-unit hz for Hz)");
}

FrfData parse_frf_csv(std::istream& in, const std::string& name, Domain domain) {
  return parse_frf(in, name, domain, FrequencyUnits{});
}

FrfData read_frf_csv(const std::string& path, Domain domain, const FrequencyUnits& units) {
  check_readable_file(path, "FRF file");
  std::ifstream f(path);
  if (!f) input_error(path, std::string("cannot open FRF file (") + std::strerror(errno) + ")");
  // The line count first (one pass over a file the page cache now holds), so
  // that the per-row vectors are allocated once: grown by doubling they left
  // ~25 MB of freed blocks per vector at 10⁶ rows.
  const auto lines = std::count(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>(), '\n');
  f.clear();
  f.seekg(0);
  FrfData d = parse_frf(f, path, domain, units, static_cast<size_t>(lines));
  if (units.is_default() && !units.unit_given) refuse_cycles_per_sample_grid(d, path);
  return d;
}

FrfData read_frf_csv(const std::string& path, Domain domain) {
  FrequencyUnits rad;  // the library's call says rad/sample (rad/s): no guard
  rad.unit_given = true;
  return read_frf_csv(path, domain, rad);
}

namespace {
// A header's non-empty names, for messages: "uEst, uVal, yEst, yVal, Ts".
std::string header_names(const std::vector<std::string>& header) {
  std::string names;
  for (const std::string& h : header)
    if (!h.empty()) names += (names.empty() ? "" : ", ") + h;
  return names;
}
}  // namespace

Eigen::MatrixXd parse_records_csv(std::istream& in, const std::string& name, int& inputs) {
  const CsvHeader csv = read_csv_header(in, name, "u,y or u1,...,y1,...");
  const auto& header = csv.cells;
  inputs = 0;
  int outputs = 0;
  for (size_t c = 0; c < header.size(); ++c) {
    const std::string& h = header[c];
    const bool is_u = !h.empty() && h[0] == 'u', is_y = !h.empty() && h[0] == 'y';
    const std::string rest = h.empty() ? "" : h.substr(1);
    const bool index_ok = rest.empty() || rest.find_first_not_of("0123456789") == std::string::npos;
    if (!(is_u || is_y) || !index_ok) {
      // Most measured files name their columns (uEst, Force, ...): the fix is
      // the options, not an edit of the file (a user review).
      input_error(name + " line 1", "column " + std::to_string(c + 1) + " \"" + h +
                                        "\" is not u, y, u<k> or y<k>; the header is " + header_names(header) +
                                        ": name the columns to use with --input NAME --output NAME (or write the "
                                        "header u,y or u1,...,y1,...)");
    }
    if (is_u) {
      if (outputs > 0) input_error(name + " line 1", "input columns must come before output columns");
      ++inputs;
    } else {
      ++outputs;
    }
  }
  if (inputs < 1 || outputs < 1) input_error(name + " line 1", "needs at least one u and one y column");
  const size_t cols = header.size();
  std::vector<double> values;
  for_each_csv_row(in, name, csv, [&](const std::vector<std::string>& cells, const std::string& where) {
    for (size_t c = 0; c < cols; ++c) values.push_back(parse_cell(cells[c], where + " column " + header[c]));
  });
  const Eigen::Index rows = static_cast<Eigen::Index>(values.size() / cols);
  if (rows == 0) input_error(name, "no samples");
  return Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), rows, static_cast<Eigen::Index>(cols));
}

Eigen::MatrixXd parse_records_csv(std::istream& in, const std::string& name, int& inputs,
                                  const RecordSelection& selection) {
  if (selection.inputs.empty() && selection.outputs.empty()) return parse_records_csv(in, name, inputs);
  if (selection.inputs.empty() || selection.outputs.empty())
    input_error(selection.inputs.empty() ? "--output" : "--input",
                "give the input columns (--input NAME) and the output columns (--output NAME) together");
  const CsvHeader csv = read_csv_header(in, name, "with the columns named by --input and --output");
  const auto& header = csv.cells;
  std::vector<size_t> chosen;
  auto find = [&](const std::string& want, const char* option) {
    const auto at = std::find(header.begin(), header.end(), want);
    if (at == header.end())
      input_error(name + " line 1",
                  std::string(option) + " \"" + want + "\" is not a column of the header (" + header_names(header) + ")");
    const size_t c = static_cast<size_t>(at - header.begin());
    if (std::find(chosen.begin(), chosen.end(), c) != chosen.end())
      input_error(option, "column \"" + want + "\" is chosen twice");
    chosen.push_back(c);
  };
  for (const auto& h : selection.inputs) find(h, "--input");
  for (const auto& h : selection.outputs) find(h, "--output");
  inputs = static_cast<int>(selection.inputs.size());
  std::vector<double> values;
  for_each_csv_row(in, name, csv, [&](const std::vector<std::string>& cells, const std::string& where) {
    for (size_t c : chosen) values.push_back(parse_cell(cells[c], where + " column " + header[c]));
  });
  const size_t cols = chosen.size();
  const Eigen::Index rows = static_cast<Eigen::Index>(values.size() / cols);
  if (rows == 0) input_error(name, "no samples");
  return Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), rows, static_cast<Eigen::Index>(cols));
}

Records read_records(const std::string& data_path, const std::string& meta_path, const RecordSelection& selection) {
  Records r;
  r.meta = read_meta(meta_path);
  const int skip = selection.skip_periods;
  if (skip < 0) input_error("--skip-periods", "must be 0 or more");
  if (skip >= r.meta.periods)
    input_error("--skip-periods", std::to_string(skip) + " leaves no period of the " + std::to_string(r.meta.periods) +
                                      " that " + meta_path + " lists");
  const int use = selection.use_periods;
  if (use < 0 || use > r.meta.periods - skip)
    input_error("--use-periods", std::to_string(use) + " is not between 1 and the " +
                                     std::to_string(r.meta.periods - skip) + " periods that remain of the " +
                                     std::to_string(r.meta.periods) + " that " + meta_path + " lists" +
                                     (skip > 0 ? " after --skip-periods " + std::to_string(skip) : std::string()));
  check_readable_file(data_path, "data file");
  std::ifstream f(data_path);
  if (!f) input_error(data_path, std::string("cannot open data file (") + std::strerror(errno) + ")");
  r.samples = parse_records_csv(f, data_path, r.inputs, selection);
  if (skip > 0) {
    const Eigen::Index drop = static_cast<Eigen::Index>(skip) * r.meta.period;
    if (r.samples.rows() <= drop)
      input_error(data_path, "has " + std::to_string(r.samples.rows()) + " samples; --skip-periods " +
                                 std::to_string(skip) + " drops " + std::to_string(drop));
    r.samples = Eigen::MatrixXd(r.samples.bottomRows(r.samples.rows() - drop));
    r.meta.periods -= skip;
  }
  if (use > 0) {
    const Eigen::Index keep = static_cast<Eigen::Index>(use) * r.meta.period;
    if (r.samples.rows() < keep)
      input_error(data_path, "has " + std::to_string(r.samples.rows()) + " samples after the skipped periods; " +
                                 "--use-periods " + std::to_string(use) + " needs " + std::to_string(keep));
    r.samples = Eigen::MatrixXd(r.samples.topRows(keep));
    r.meta.periods = use;
  }
  return r;
}

Eigen::MatrixXd read_records_csv(const std::string& path, int& inputs) {
  check_readable_file(path, "data file");
  std::ifstream f(path);
  if (!f) input_error(path, std::string("cannot open data file (") + std::strerror(errno) + ")");
  return parse_records_csv(f, path, inputs);
}

namespace {
// The meta's fields (the contracts' format).
const std::array<const char*, 4> kMetaFields = {"period", "periods", "sample_time", "excited_lines"};

// A missing field names a present unknown one that is one or two edits away
// (review finding 8 of stop 47: "peroid" for "period" gave "is missing" alone;
// "periods", a field of its own, is no misspelling of "period").
std::string misspelling_hint(const nlohmann::json& j, const std::string& key) {
  for (const auto& item : j.items())
    if (std::find(kMetaFields.begin(), kMetaFields.end(), item.key()) == kMetaFields.end() &&
        edit_distance(item.key(), key) <= 2)
      return " (is \"" + item.key() + "\" a misspelling of it?)";
  return "";
}

int int_field(const nlohmann::json& j, const std::string& key, const std::string& where) {
  if (!j.contains(key)) input_error(where + " field \"" + key + "\"", "is missing" + misspelling_hint(j, key));
  const auto& v = j.at(key);
  if (!v.is_number_integer() && !(v.is_number() && std::floor(v.get<double>()) == v.get<double>()))
    input_error(where + " field \"" + key + "\"", "must be an integer");
  const double x = v.get<double>();
  if (std::abs(x) > 2e9) input_error(where + " field \"" + key + "\"", "is out of range");
  return static_cast<int>(x);
}
}  // namespace

RecordMeta meta_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) input_error(where, "expected a JSON object");
  RecordMeta m;
  m.period = int_field(j, "period", where);
  m.periods = int_field(j, "periods", where);
  // Required, as in the contracts' meta format (review finding 12: a meta
  // without it was taken as Ts = 1 s).
  if (!j.contains("sample_time"))
    input_error(where + " field \"sample_time\"", "is missing" + misspelling_hint(j, "sample_time") +
                                                  ": the sample period in seconds (1.0 when time is counted in samples)");
  m.sample_time = number_from_json(j["sample_time"], where + " field \"sample_time\"");
  if (m.period < 2) input_error(where + " field \"period\"", "must be at least 2, got " + std::to_string(m.period));
  if (m.periods < 1) input_error(where + " field \"periods\"", "must be at least 1, got " + std::to_string(m.periods));
  if (!(m.sample_time > 0)) input_error(where + " field \"sample_time\"", "must be positive");
  if (!j.contains("excited_lines"))
    input_error(where + " field \"excited_lines\"",
                "is missing" + misspelling_hint(j, "excited_lines") + ": the DFT lines k = 1 ... P/2 the excitation drives");
  if (!j["excited_lines"].is_array())
    input_error(where + " field \"excited_lines\"", "must be an array of DFT line indices");
  for (size_t i = 0; i < j["excited_lines"].size(); ++i) {
    const auto& v = j["excited_lines"][i];
    const std::string w = where + " field \"excited_lines\"[" + std::to_string(i) + "]";
    if (!v.is_number() || std::floor(v.get<double>()) != v.get<double>()) input_error(w, "must be an integer");
    const double k = v.get<double>();
    if (k < 1 || k > m.period / 2)
      input_error(w, "line " + v.dump() + " is outside 1 ... P/2 = " +
                         std::to_string(m.period / 2));
    m.excited_lines.push_back(static_cast<int>(k));
  }
  if (m.excited_lines.empty()) input_error(where + " field \"excited_lines\"", "no excited lines");
  return m;
}

RecordMeta read_meta(const std::string& path) {
  return meta_from_json(read_json_file(path, "meta file"), path);
}

nlohmann::json frf_result_to_json(const FrfResult& r, const std::string& method) {
  nlohmann::json j = model_to_json(r.model);
  j["order"] = r.order;
  j["method"] = method;
  j["r"] = r.r;
  if (r.omega_scale > 0) j["omega_scale"] = r.omega_scale;  // what check needs to repeat Algorithm 2
  j["singular_values"] =
      std::vector<double>(r.singular_values.data(), r.singular_values.data() + r.singular_values.size());
  j["singular_values_of"] = "C_Y^{-1/2} R22^T (Pintelon 2002 step 1c), r = " + std::to_string(r.order_r);
  nlohmann::json poles = nlohmann::json::array();
  for (Eigen::Index i = 0; i < r.poles.size(); ++i) poles.push_back({r.poles(i).real(), r.poles(i).imag()});
  j["poles"] = poles;
  j["v_sub"] = r.v_sub;
  nlohmann::json scan = nlohmann::json::array();
  for (const auto& [rr, v] : r.r_scan) scan.push_back({{"r", rr}, {"v_sub", v}});
  j["r_scan"] = scan;
  if (r.r_unusable_least_v_sub > 0) j["r_unusable_least_v_sub"] = r.r_unusable_least_v_sub;
  j["diagnostics"] = {{"condition", r.condition},
                      {"error_estimate", r.error_estimate},
                      {"error_estimate_of", r.error_estimate_of},
                      {"usable", usable_precision(r.usability_estimate())},
                      {"noise_edge", r.noise_edge}};
  if (r.rounding_assessed) {
    // Infinite (null in JSON) when a rounding-size move made the estimate fail; the warning says which step.
    j["diagnostics"]["g_error_estimate"] = r.g_error_estimate;
    j["diagnostics"]["pole_error_estimate"] = r.pole_error_estimate;
    j["diagnostics"]["usable_from"] =
        "the larger of g_error_estimate (G on the data's frequencies) and pole_error_estimate: " + r.rounding_moves;
  }
  j["warnings"] = r.warnings;
  j["notes"] = r.notes;
  return j;
}

std::string records_csv(const Eigen::MatrixXd& samples) {
  std::ostringstream csv;
  csv << "u,y\n";
  char buf[80];
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g,%.17g\n", samples(i, 0), samples(i, 1));
    csv << buf;
  }
  return csv.str();
}

nlohmann::json meta_to_json(const RecordMeta& meta) {
  return {{"period", meta.period},
          {"periods", meta.periods},
          {"sample_time", meta.sample_time},
          {"excited_lines", meta.excited_lines}};
}

namespace {

// The file an output path names: a symbolic link is followed (up to 40 links,
// the kernel's limit), so that the file written is the link's target and the
// link stays; a dangling link names the file it points to.
std::filesystem::path output_target(const std::string& path) {
  namespace fs = std::filesystem;
  fs::path p(path);
  std::error_code ec;
  for (int links = 0; links < 40 && fs::is_symlink(fs::symlink_status(p, ec)); ++links) {
    const fs::path to = fs::read_symlink(p, ec);
    if (ec) break;
    p = to.is_absolute() ? to : p.parent_path() / to;
  }
  return p;
}

// An existing output that is not a regular file (a device such as /dev/null,
// a FIFO): written in place, not replaced by a renamed temporary.
bool special_file(const std::filesystem::path& p) {
  std::error_code ec;
  const auto st = std::filesystem::status(p, ec);
  return !ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) &&
         !std::filesystem::is_directory(st);
}

}  // namespace

void require_writable_path(const std::string& path, const std::string& option) {
  if (path == "-") return;
  namespace fs = std::filesystem;
  const fs::path target = output_target(path);
  if (special_file(target)) {
    if (access(target.c_str(), W_OK) != 0)
      input_error(option, "\"" + path + "\" is not writable (" + std::strerror(errno) + ")");
    return;
  }
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    input_error(option, "folder \"" + dir.string() + "\" of \"" + path + "\" does not exist (create it first)");
  if (fs::is_directory(target, ec)) input_error(option, "\"" + path + "\" is a folder: give a file name");
  if (access(dir.c_str(), W_OK) != 0)
    input_error(option, "folder \"" + dir.string() + "\" is not writable (" + std::strerror(errno) + ")");
}

void write_text_file(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text;
    std::cout.flush();
    return;
  }
  // A new or regular file is written whole or not at all: a temporary beside
  // it, renamed into place (a link's target, the link kept); a device or FIFO
  // is written in place (renaming would replace /dev/null by a file).
  const std::filesystem::path target = output_target(path);
  if (special_file(target)) {
    std::ofstream f(target, std::ios::binary);
    if (!f) input_error(path, "cannot write output file");
    f << text;
    f.flush();
    if (!f) input_error(path, "write failed");
    return;
  }
  const std::string tmp = target.string() + ".tmp-fdsid";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) input_error(path, "cannot write output file");
    f << text;
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      input_error(path, "write failed");
    }
  }
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    std::remove(tmp.c_str());
    input_error(path, "cannot rename the temporary output into place");
  }
}

}  // namespace fdsid
