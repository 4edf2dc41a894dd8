// Model JSON, power-spectrum CSV and frequency-response CSV (shared/CONTRACTS.md)
// in high precision.
// No Eigen decomposition is instantiated here (see spectrum_id.cpp).
#include "fdsid/reference/io.hpp"

#include <boost/math/constants/constants.hpp>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>

namespace fdsid::reference {
namespace {

using nlohmann::json;

std::string trim(const std::string& text) {
  std::size_t begin = 0, end = text.size();
  while (begin < end && std::isspace(static_cast<unsigned char>(text[begin]))) ++begin;
  while (end > begin && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  return text.substr(begin, end - begin);
}

// [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?
bool is_decimal(const std::string& text) {
  std::size_t i = 0;
  const std::size_t n = text.size();
  auto digits = [&]() {
    const std::size_t start = i;
    while (i < n && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
    return i - start;
  };
  if (i < n && (text[i] == '+' || text[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < n && text[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < n && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < n && (text[i] == '+' || text[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == n;
}

// The shortest decimal that reads back as x (glibc printf is correctly
// rounded). For a number written with ≤ 15 significant digits this is exactly
// the text that was written: two distinct such decimals never share a double.
std::string shortest_decimal(double x) {
  char buffer[64];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buffer, sizeof buffer, "%.*e", digits - 1, x);
    if (std::strtod(buffer, nullptr) == x) break;
  }
  return buffer;
}

Real json_to_real(const json& value, const std::string& where) {
  if (value.is_string()) {
    try {
      return parse_decimal(value.get<std::string>());
    } catch (const InputError& e) {
      throw InputError(where + ": " + e.what());
    }
  }
  if (value.is_number_integer()) {
    if (value.is_number_unsigned()) return Real(value.get<std::uint64_t>());
    return Real(value.get<std::int64_t>());
  }
  if (value.is_number_float()) {
    const double x = value.get<double>();
    if (!std::isfinite(x)) throw InputError(where + ": not a finite number");
    return parse_decimal(shortest_decimal(x));
  }
  throw InputError(where + ": expected a number or a decimal string, got " + value.dump());
}

MatrixR matrix_field(const json& model, const std::string& name) {
  if (!model.contains(name)) throw InputError("model: missing field \"" + name + "\"");
  const json& rows = model.at(name);
  if (!rows.is_array() || rows.empty())
    throw InputError("model: field \"" + name + "\" must be a non-empty array of rows");
  std::size_t cols = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].is_array() || rows[i].empty())
      throw InputError("model: field \"" + name + "\" row " + std::to_string(i + 1) +
                       " must be a non-empty array");
    if (i == 0) cols = rows[i].size();
    if (rows[i].size() != cols)
      throw InputError("model: field \"" + name + "\" row " + std::to_string(i + 1) + " has " +
                       std::to_string(rows[i].size()) + " entries, row 1 has " + std::to_string(cols));
  }
  MatrixR X(rows.size(), cols);
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < cols; ++j)
      X(i, j) = json_to_real(rows[i][j], "model: field \"" + name + "\" row " + std::to_string(i + 1) +
                                             " column " + std::to_string(j + 1));
  return X;
}

json matrix_to_json(const MatrixR& X, int digits) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < X.cols(); ++j) row.push_back(to_decimal(X(i, j), digits));
    rows.push_back(row);
  }
  return rows;
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream stream(line);
  std::string cell;
  while (std::getline(stream, cell, ',')) cells.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

std::vector<std::string> spectrum_header(int m) {
  std::vector<std::string> names{"omega"};
  if (m == 1) {
    names.push_back("S_re");
    names.push_back("S_im");
    return names;
  }
  for (int a = 1; a <= m; ++a)
    for (int b = 1; b <= m; ++b) {
      const std::string entry = "S" + std::to_string(a) + std::to_string(b);
      names.push_back(entry + "_re");
      names.push_back(entry + "_im");
    }
  return names;
}


using Fail = std::function<void(int, const std::string&)>;

// InputError "<path>:<line>: <what>", the one form of every CSV error.
[[noreturn]] void fail_at(const std::string& path, int line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ": " + what);
}

// The one reader of the decimal CSV formats (spectra, FRF, records): the first
// non-blank line is the header, which `header` checks and maps to the column
// names used in messages; every further non-blank line must have as many
// cells, each parsed exactly by parse_decimal, and goes to `row`. Errors throw
// InputError "<path>:<line>: …". Returns the last line number read.
int read_decimal_csv(const std::string& path,
                     const std::function<std::vector<std::string>(const std::vector<std::string>&, int, const Fail&)>& header,
                     const std::function<void(const std::vector<Real>&, const std::vector<std::string>&, int, const Fail&)>& row) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open");
  const Fail fail = [&](int line, const std::string& what) { fail_at(path, line, what); };
  std::string line;
  int line_number = 0;
  std::vector<std::string> names;
  while (std::getline(in, line)) {
    ++line_number;
    if (!trim(line).empty()) {
      names = split_csv(trim(line));
      break;
    }
  }
  names = header(names, line_number, fail);
  const std::size_t cols = names.size();
  while (std::getline(in, line)) {
    ++line_number;
    if (trim(line).empty()) continue;
    const std::vector<std::string> cells = split_csv(trim(line));
    if (cells.size() != cols)
      fail(line_number, std::to_string(cells.size()) + " cells, header has " + std::to_string(cols));
    std::vector<Real> values(cols);
    for (std::size_t c = 0; c < cols; ++c) {
      try {
        values[c] = parse_decimal(cells[c]);
      } catch (const InputError& e) {
        fail(line_number, "column " + names[c] + ": " + e.what());
      }
    }
    row(values, cells, line_number, fail);
  }
  return line_number;
}

}  // namespace

Real parse_decimal(const std::string& text) {
  const std::string t = trim(text);
  if (!is_decimal(t)) throw InputError("not a decimal number: '" + text + "'");
  // Boost converts the full decimal text exactly (integer arithmetic), then rounds once.
  return Real(t[0] == '+' ? t.substr(1) : t);
}

std::string to_decimal(const Real& x, int digits) {
  return x.str(std::max(digits, 1) - 1, std::ios_base::scientific);
}

Model model_from_json(const json& j) {
  if (!j.is_object()) throw InputError("model: expected a JSON object");
  Model model;
  // "domain" always, "sample_time" for a discrete-time model: both are part of
  // the model format (none is assumed).
  if (!j.contains("domain"))
    throw InputError("model: field \"domain\" is missing: add \"domain\": \"discrete\" or \"continuous\"");
  if (!j.at("domain").is_string()) throw InputError("model: field \"domain\" must be a string");
  model.domain = j.at("domain").get<std::string>();
  if (model.domain != "discrete" && model.domain != "continuous")
    throw InputError("model: field \"domain\" must be \"discrete\" or \"continuous\", got \"" +
                     model.domain + "\"");
  if (j.contains("sample_time")) {
    model.sample_time = json_to_real(j.at("sample_time"), "model: field \"sample_time\"");
    // 0 is a continuous-time model's "no sample period" (what identify_frf writes).
    if (!(model.sample_time > 0) && !(model.domain == "continuous" && model.sample_time == 0))
      throw InputError("model: field \"sample_time\" must be positive (or 0 for a continuous-time model)");
  } else if (model.domain == "discrete") {
    throw InputError("model: field \"sample_time\" is missing: a discrete-time model needs its sample time "
                     "in seconds (1.0 when time is counted in samples)");
  }
  model.A = matrix_field(j, "A");
  model.B = matrix_field(j, "B");
  model.C = matrix_field(j, "C");
  model.D = matrix_field(j, "D");
  const auto n = model.A.rows();
  if (model.A.cols() != n) throw InputError("model: A is not square");
  if (model.B.rows() != n) throw InputError("model: B has " + std::to_string(model.B.rows()) +
                                            " rows, A has " + std::to_string(n));
  if (model.C.cols() != n) throw InputError("model: C has " + std::to_string(model.C.cols()) +
                                            " columns, A has " + std::to_string(n));
  if (model.D.rows() != model.C.rows() || model.D.cols() != model.B.cols())
    throw InputError("model: D must be " + std::to_string(model.C.rows()) + "x" +
                     std::to_string(model.B.cols()) + " (rows of C x columns of B)");
  return model;
}

json model_to_json(const Model& model, int digits) {
  json j;
  j["domain"] = model.domain;
  j["sample_time"] = to_decimal(model.sample_time, digits);
  j["A"] = matrix_to_json(model.A, digits);
  j["B"] = matrix_to_json(model.B, digits);
  j["C"] = matrix_to_json(model.C, digits);
  j["D"] = matrix_to_json(model.D, digits);
  return j;
}

Model read_model(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(path + ": invalid JSON: " + e.what());
  }
  try {
    return model_from_json(j);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
}

json result_to_json(const Result& result, bool van_overschee, int digits) {
  json j = model_to_json(result.model, digits);
  j["order"] = result.order;
  j["method"] = van_overschee ? "vo1997" : "akcay2011";
  j["p"] = result.p;
  j["r"] = result.r;
  json sigma = json::array();
  for (const Real& s : van_overschee ? result.singular_values_vo : result.singular_values_Y)
    sigma.push_back(to_decimal(s, digits));
  j["singular_values"] = sigma;
  json poles = json::array();
  for (const Complex& z : result.poles)
    poles.push_back(json::array({to_decimal(z.real(), digits), to_decimal(z.imag(), digits)}));
  j["poles"] = poles;
  j["E"] = matrix_to_json(result.E, digits);
  j["F"] = matrix_to_json(result.F, digits);
  j["P"] = matrix_to_json(result.P, digits);
  return j;
}

namespace {

// The header of the power-spectrum CSV: omega then S_re,S_im (m = 1; also
// S11_re,S11_im) or S11_re,S11_im,…,Smm_im, i.e. 1 + 2m² columns, optionally
// followed by S_var (the samples' noise variance, which only fast/'s
// refinement reads: parsed, not used here). Returns m; `fail` (which throws)
// on any other header.
int spectrum_header_size(const std::vector<std::string>& header_in, int header_line, const Fail& fail, bool& has_var) {
  if (header_in.empty()) fail(header_line, "empty file, expected header omega,S_re,S_im,...");
  has_var = header_in.back() == "S_var";
  std::vector<std::string> header = header_in;
  if (has_var) header.pop_back();
  int m = 0;
  const std::size_t cols = header.size();
  while (1 + 2 * static_cast<std::size_t>(m + 1) * (m + 1) <= cols) ++m;
  if (m < 1 || 1 + 2 * static_cast<std::size_t>(m) * m != cols)
    fail(header_line, std::to_string(cols) + " columns; expected 1 + 2m^2 (omega,S_re,S_im for m = 1)");
  const std::vector<std::string> expected = spectrum_header(m);
  bool matches = header == expected;
  if (!matches && m == 1) matches = header == std::vector<std::string>{"omega", "S11_re", "S11_im"};
  if (!matches) {
    std::string want;
    for (const std::string& name : expected) want += (want.empty() ? "" : ",") + name;
    fail(header_line, "header must be " + want);
  }
  return m;
}

// The omegas read must lie on ω_k = π(k−1)/M, k = 1 … M+1, to within 1e-9·π
// (Eq. 7 of Akçay 2011; the algorithm uses the exact grid, not these values).
void check_uniform_grid(const std::string& path, const std::vector<Real>& omega,
                        const std::vector<int>& omega_line, int M) {
  const Real pi = boost::math::constants::pi<Real>();
  const Real tolerance = Real("1e-9") * pi;
  for (std::size_t k = 0; k < omega.size(); ++k) {
    const Real grid = pi * Real(static_cast<int>(k)) / Real(M);
    if (abs(omega[k] - grid) > tolerance)
      fail_at(path, omega_line[k], "omega = " + to_decimal(omega[k], 17) + " is off the uniform grid pi(k-1)/M = " +
                                       to_decimal(grid, 17) + " (k = " + std::to_string(k + 1) +
                                       ", M = " + std::to_string(M) + ")");
  }
}

}  // namespace

Spectrum read_spectrum_csv(const std::string& path) {
  std::vector<Real> omega;
  std::vector<int> omega_line;
  Spectrum spectrum;
  int m = 0;
  bool has_var = false;
  const int line_number = read_decimal_csv(
      path,
      [&](const std::vector<std::string>& header, int header_line, const Fail& fail) {
        m = spectrum_header_size(header, header_line, fail, has_var);
        std::vector<std::string> names = spectrum_header(m);
        if (has_var) names.push_back("S_var");
        return names;
      },
      [&](const std::vector<Real>& values, const std::vector<std::string>&, int line, const Fail&) {
        MatrixC S(m, m);
        for (int a = 0; a < m; ++a)
          for (int b = 0; b < m; ++b) {
            const std::size_t c = 1 + 2 * static_cast<std::size_t>(a * m + b);
            S(a, b) = Complex(values[c], values[c + 1]);
          }
        omega.push_back(values[0]);
        omega_line.push_back(line);
        spectrum.S.push_back(S);
      });
  spectrum.m = m;
  if (spectrum.S.size() < 2)
    fail_at(path, line_number, "need at least 2 samples (M >= 1), got " + std::to_string(spectrum.S.size()));
  spectrum.M = static_cast<int>(spectrum.S.size()) - 1;
  check_uniform_grid(path, omega, omega_line, spectrum.M);
  return spectrum;
}

void write_spectrum_csv(const Spectrum& spectrum, const std::string& path, int digits) {
  if (spectrum.m < 1 || spectrum.M < 1 || static_cast<int>(spectrum.S.size()) != spectrum.M + 1)
    throw InputError(path + ": spectrum to write is malformed (need m >= 1, M >= 1, M + 1 samples)");
  // Written to a temporary file beside the target, then renamed into place: an
  // interrupted or failing run never leaves a half-written or clobbered file.
  const std::string tmp = path + ".tmp-fdsid";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw InputError(path + ": cannot open for writing");
    const std::vector<std::string> names = spectrum_header(spectrum.m);
    for (std::size_t c = 0; c < names.size(); ++c) out << (c ? "," : "") << names[c];
    out << '\n';
    const Real pi = boost::math::constants::pi<Real>();
    for (int k = 0; k <= spectrum.M; ++k) {
      out << to_decimal(pi * Real(k) / Real(spectrum.M), digits);
      for (int a = 0; a < spectrum.m; ++a)
        for (int b = 0; b < spectrum.m; ++b)
          out << ',' << to_decimal(spectrum.S[k](a, b).real(), digits) << ','
              << to_decimal(spectrum.S[k](a, b).imag(), digits);
      out << '\n';
    }
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw InputError(path + ": write failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw InputError(path + ": cannot rename the temporary output into place");
  }
}

FrfData read_frf_csv(const std::string& path, const std::string& domain) {
  if (domain != "discrete" && domain != "continuous")
    throw InputError(path + ": domain \"" + domain + "\" is neither discrete nor continuous");
  FrfData data;
  data.domain = domain;
  const int line_number = read_decimal_csv(
      path,
      [](const std::vector<std::string>& header, int line, const Fail& fail) {
        const std::vector<std::string> plain = {"omega", "G_re", "G_im"};
        const std::vector<std::string> with_var = {"omega", "G_re", "G_im", "G_var"};
        if (header != plain && header != with_var)
          fail(line, "header must be omega,G_re,G_im or omega,G_re,G_im,G_var");
        return header;
      },
      [&](const std::vector<Real>& values, const std::vector<std::string>& cells, int line, const Fail& fail) {
        const Real variance = values.size() == 4 ? values[3] : Real(1);
        if (!(variance > 0)) fail(line, "G_var = " + cells[3] + " is not > 0");
        data.omega.push_back(values[0]);
        data.U.push_back(MatrixC::Constant(1, 1, Complex(1)));
        data.Y.push_back(MatrixC::Constant(1, 1, Complex(values[1], values[2])));
        data.variance.push_back(MatrixR::Constant(1, 1, variance));
      });
  if (data.omega.empty()) fail_at(path, line_number, "no samples");
  return data;
}

Records read_records_csv(const std::string& path) {
  Records records;
  const int line_number = read_decimal_csv(
      path,
      [](const std::vector<std::string>& header, int line, const Fail& fail) {
        if (header != std::vector<std::string>{"u", "y"}) fail(line, "header must be u,y (one input, one output)");
        return header;
      },
      [&](const std::vector<Real>& values, const std::vector<std::string>&, int, const Fail&) {
        records.u.push_back(values[0]);
        records.y.push_back(values[1]);
      });
  if (records.u.empty()) fail_at(path, line_number, "no samples");
  return records;
}

}  // namespace fdsid::reference
