#include "fdsid/io.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include "fdsid/error.hpp"

namespace fdsid {

namespace {

[[noreturn]] void input_error(const std::string& where, const std::string& what) {
  throw Error(ErrorKind::Input, where, what);
}

double number_from_json(const nlohmann::json& v, const std::string& where) {
  if (v.is_number()) {
    const double x = v.get<double>();
    if (!std::isfinite(x)) input_error(where, "not a finite number");
    return x;
  }
  if (v.is_string()) {
    const std::string s = v.get<std::string>();
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size()) input_error(where, "\"" + s + "\" is not a decimal number");
    if (!std::isfinite(x) || (errno == ERANGE && std::abs(x) > 1.0))
      input_error(where, "\"" + s + "\" is not a finite double");
    return x;
  }
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
    if (!v[i].is_array() || v[i].size() != cols)
      input_error(w, "row " + std::to_string(i + 1) + " has " +
                         (v[i].is_array() ? std::to_string(v[i].size()) : std::string("no")) + " entries, expected " +
                         std::to_string(cols));
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

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream s(line);
  while (std::getline(s, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    size_t b = 0;
    while (b < cell.size() && cell[b] == ' ') ++b;
    out.push_back(cell.substr(b));
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double parse_cell(const std::string& cell, const std::string& where) {
  if (cell.empty()) input_error(where, "empty value");
  char* end = nullptr;
  const double x = std::strtod(cell.c_str(), &end);
  if (end != cell.c_str() + cell.size()) input_error(where, "\"" + cell + "\" is not a number");
  if (!std::isfinite(x)) input_error(where, "\"" + cell + "\" is not finite (NaN and Inf are not data)");
  return x;
}

}  // namespace

StateSpace model_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) input_error(where, "expected a JSON object");
  StateSpace m;
  if (j.contains("domain")) {
    if (!j["domain"].is_string()) input_error(where + " field \"domain\"", "must be \"discrete\" or \"continuous\"");
    const std::string d = j["domain"];
    if (d == "discrete") m.domain = Domain::Discrete;
    else if (d == "continuous") m.domain = Domain::Continuous;
    else input_error(where + " field \"domain\"", "\"" + d + "\" is neither \"discrete\" nor \"continuous\"");
  }
  if (j.contains("sample_time")) m.sample_time = number_from_json(j["sample_time"], where + " field \"sample_time\"");
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
  return m;
}

namespace {
void check_readable_file(const std::string& path, const char* what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) input_error(path, std::string("is a directory, not a ") + what);
}
}  // namespace

StateSpace read_model(const std::string& path) {
  check_readable_file(path, "model file");
  std::ifstream f(path);
  if (!f) input_error(path, "cannot open model file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(f);
  } catch (const nlohmann::json::parse_error& e) {
    input_error(path, std::string("malformed JSON: ") + e.what());
  }
  return model_from_json(j, path);
}

nlohmann::json model_to_json(const StateSpace& m) {
  return {{"domain", to_string(m.domain)}, {"sample_time", m.sample_time}, {"A", matrix_to_json(m.A)},
          {"B", matrix_to_json(m.B)},       {"C", matrix_to_json(m.C)},       {"D", matrix_to_json(m.D)}};
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
  nlohmann::json poles = nlohmann::json::array();
  for (const cplx& z : fdsid::poles(r.model)) poles.push_back({z.real(), z.imag()});
  j["poles"] = poles;
  j["summands"] = {{"E", matrix_to_json(r.summands.E)}, {"F", matrix_to_json(r.summands.F)},
                   {"P", matrix_to_json(r.summands.P)}};
  j["diagnostics"] = {{"split_margin", r.split_margin},
                      {"min_spectrum_on_grid", r.min_spectrum},
                      {"max_zero_modulus", r.max_zero_modulus},
                      {"riccati_method", r.riccati_method},
                      {"riccati_iterations", r.riccati_iterations},
                      {"riccati_residual", r.riccati_residual}};
  return j;
}

SpectrumData parse_spectrum_csv(std::istream& in, const std::string& name) {
  std::string line;
  if (!std::getline(in, line)) input_error(name, "empty file (expected a header omega,S_re,S_im)");
  const auto header = split_csv(line);
  const auto cols = header.size();
  if (cols < 3 || (cols - 1) % 2 != 0 || header[0] != "omega")
    input_error(name + " line 1", "header must be omega,S_re,S_im or omega,S11_re,S11_im,...,Smm_re,Smm_im");
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
  std::vector<double> omega;
  std::vector<cplx> values;
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    const auto cells = split_csv(line);
    const std::string where = name + " line " + std::to_string(lineno);
    if (cells.size() != cols)
      input_error(where, "has " + std::to_string(cells.size()) + " fields, the header has " + std::to_string(cols));
    omega.push_back(parse_cell(cells[0], where + " column omega"));
    for (int e = 0; e < entries; ++e)
      values.emplace_back(parse_cell(cells[1 + 2 * e], where + " column " + header[1 + 2 * e]),
                          parse_cell(cells[2 + 2 * e], where + " column " + header[2 + 2 * e]));
  }
  if (omega.size() < 2) input_error(name, "needs at least 2 samples (M >= 1), found " + std::to_string(omega.size()));
  SpectrumData d;
  d.m = m;
  d.M = static_cast<int>(omega.size()) - 1;
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
  for (int k = 0; k <= d.M; ++k)
    for (int e = 0; e < entries; ++e) {
      const int a = e / m, b = e % m;  // CSV is row-major; S stores vec() column-major
      d.S(a + m * b, k) = values[static_cast<size_t>(k) * entries + e];
    }
  return d;
}

SpectrumData read_spectrum_csv(const std::string& path) {
  check_readable_file(path, "spectrum file");
  std::ifstream f(path);
  if (!f) input_error(path, "cannot open spectrum file");
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
    out << '\n';
  }
}

void write_text_file(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::cout << text;
    std::cout.flush();
    return;
  }
  const std::string tmp = path + ".tmp-fdsid";
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
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    input_error(path, "cannot rename the temporary output into place");
  }
}

}  // namespace fdsid
