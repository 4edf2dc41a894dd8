// Model JSON and spectrum CSV readers of the contracts.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "fdsid/error.hpp"
#include "fdsid/io.hpp"

namespace fdsid {
namespace {

TEST(ModelJson, ParsesNumbersAndDecimalStrings) {
  const auto j = nlohmann::json::parse(R"({"domain":"discrete","sample_time":"0.5",
      "A":[["0.8876"]],"B":[[1]],"C":[["-2.5e-1"]],"D":[[1]]})");
  const StateSpace m = model_from_json(j);
  // strtod rounds correctly: "0.8876" gives the same double as the literal.
  EXPECT_EQ(m.A(0, 0), 0.8876);
  EXPECT_EQ(m.C(0, 0), -0.25);
  EXPECT_EQ(m.sample_time, 0.5);
}

TEST(ModelJson, RoundTripsExactly) {
  StateSpace m;
  m.A = Eigen::MatrixXd::Random(3, 3) * 0.3;
  m.B = Eigen::MatrixXd::Random(3, 2);
  m.C = Eigen::MatrixXd::Random(2, 3);
  m.D = Eigen::MatrixXd::Random(2, 2);
  const StateSpace back = model_from_json(nlohmann::json::parse(model_to_json(m).dump()));
  EXPECT_EQ(back.A, m.A);  // nlohmann prints doubles with round-trip precision
  EXPECT_EQ(back.D, m.D);
}

TEST(ModelJson, RejectsMalformedModels) {
  // Each text is a valid model but for the one defect named beside it, and the
  // message must name that defect (not merely throw).
  const struct {
    const char* text;
    const char* names;
  } bad[] = {
      {R"({"domain":"discrete","sample_time":1,"A":[[1]],"B":[[1]],"C":[[1]]})", "field \"D\" is missing"},
      {R"({"domain":"discrete","sample_time":1,"A":[[1,2]],"B":[[1]],"C":[[1]],"D":[[1]]})", "square"},
      {R"({"domain":"discrete","sample_time":1,"A":[["x"]],"B":[[1]],"C":[[1]],"D":[[1]]})", "not a decimal number"},
      {R"({"domain":"discrete","sample_time":1,"A":[["0x10"]],"B":[[1]],"C":[[1]],"D":[[1]]})", "hexadecimal"},
      {R"({"domain":"discrete","sample_time":1,"A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1,2]]})", "D"},
      {R"({"domain":"hybrid","sample_time":1,"A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})", "hybrid"},
      // Review finding 10: a model without domain or sample time was taken as discrete with Ts = 1.
      {R"({"sample_time":1,"A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})", "field \"domain\": is missing"},
      {R"({"domain":"discrete","A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})", "field \"sample_time\": is missing"},
      {R"([1,2])", "JSON object"},
      // A user review: "order": 3 beside a 4-state A was accepted silently.
      {R"({"domain":"discrete","sample_time":1,"order":2,"A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})",
       "field \"order\": is 2 but A has 1 rows"},
      {R"({"domain":"discrete","sample_time":1,"order":"1","A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})",
       "not a whole number"}};
  for (const auto& c : bad) {
    try {
      model_from_json(nlohmann::json::parse(c.text), "m.json");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(c.names), std::string::npos) << c.text << " -> " << e.what();
    }
  }
}

TEST(ModelJson, AnOrderThatMatchesAIsTaken) {
  EXPECT_EQ(model_from_json(nlohmann::json::parse(
                                R"({"domain":"discrete","sample_time":1,"order":1,"A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})"))
                .order(),
            1);
}

TEST(ModelJson, AContinuousModelNeedsNoSampleTime) {
  const StateSpace m = model_from_json(
      nlohmann::json::parse(R"({"domain":"continuous","A":[[-1]],"B":[[1]],"C":[[1]],"D":[[0]]})"));
  EXPECT_EQ(m.domain, Domain::Continuous);
}

TEST(SpectrumCsv, ReadsScalarAndMimoLayouts) {
  std::istringstream s1("omega,S_re,S_im\n0,2,0\n1.5707963267948966,3,0.5\n3.141592653589793,4,0\n");
  const SpectrumData d1 = parse_spectrum_csv(s1, "s.csv");
  EXPECT_EQ(d1.m, 1);
  EXPECT_EQ(d1.M, 2);
  EXPECT_EQ(d1.at(0, 0, 1), cplx(3, 0.5));

  std::istringstream s2(
      "omega,S11_re,S11_im,S12_re,S12_im,S21_re,S21_im,S22_re,S22_im\n"
      "0,5,0,2,1,2,-1,4,0\n3.141592653589793,6,0,1,3,1,-3,7,0\n");
  const SpectrumData d2 = parse_spectrum_csv(s2, "s.csv");
  EXPECT_EQ(d2.m, 2);
  EXPECT_EQ(d2.at(0, 1, 0), cplx(2, 1));   // S12: row 1, column 2
  EXPECT_EQ(d2.at(1, 0, 1), cplx(1, -3));  // S21
}

// Review finding 8: data/mimo2x2_M64.csv with the sign of S21_im flipped was
// accepted and identified with twice the order.
TEST(SpectrumCsv, RefusesANonHermitianMimoSpectrum) {
  std::ifstream f(std::string(FDSID_SOURCE_DIR) + "/data/mimo2x2_M64.csv");
  std::string header, line;
  std::getline(f, header);
  std::ostringstream good_text, bad_text;
  good_text << header << '\n';
  bad_text << header << '\n';
  while (std::getline(f, line)) {
    good_text << line << '\n';
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string c; std::getline(row, c, ',');) cells.push_back(c);
    // S21_im is column 7 (omega, S11 re/im, S12 re/im, S21 re/im, ...).
    if (cells[6] != "0") cells[6] = cells[6][0] == '-' ? cells[6].substr(1) : "-" + cells[6];
    for (size_t i = 0; i < cells.size(); ++i) bad_text << (i ? "," : "") << cells[i];
    bad_text << '\n';
  }
  std::istringstream good(good_text.str()), bad(bad_text.str());
  EXPECT_EQ(parse_spectrum_csv(good, "mimo.csv").m, 2);
  try {
    parse_spectrum_csv(bad, "flipped.csv");
    ADD_FAILURE() << "a non-Hermitian spectrum was accepted";
  } catch (const Error& e) {
    // Line 2 (omega = 0) has S12_im = 0; line 3 is the first with a flipped sign.
    EXPECT_NE(std::string(e.what()).find("flipped.csv line 3: S21 is not conj(S12)"), std::string::npos) << e.what();
  }
}

// Review (new user): a scalar spectrum with S_im = 0.3 S_re was identified
// exactly as the clean file (the default extension discards Im S_aa). Noise
// may give the diagonal an imaginary part (the bundled Section 4 file: complex
// noise of level 1e-3, both signs), one sign at every sample it may not.
TEST(SpectrumCsv, RefusesADiagonalWhoseImaginaryPartHasOneSign) {
  std::ifstream f(std::string(FDSID_SOURCE_DIR) + "/data/akcay2011_M1000_eps1e-3.csv");
  std::ostringstream noisy_text, skewed_text;
  skewed_text << std::setprecision(17);
  std::string line;
  std::getline(f, line);
  noisy_text << line << '\n';
  skewed_text << line << '\n';
  while (std::getline(f, line)) {
    noisy_text << line << '\n';
    std::istringstream row(line);
    double omega, re, im;
    char c1, c2;
    row >> omega >> c1 >> re >> c2 >> im;
    skewed_text << omega << ',' << re << ',' << 0.3 * std::abs(re) << '\n';
  }
  std::istringstream noisy(noisy_text.str()), skewed(skewed_text.str());
  const SpectrumData d = parse_spectrum_csv(noisy, "noisy.csv");
  int positive = 0;
  for (int k = 0; k <= d.M; ++k) positive += d.at(0, 0, k).imag() > 0;
  ASSERT_GT(positive, 0);  // the noisy file carries imaginary parts of both signs
  ASSERT_LT(positive, d.M + 1);
  try {
    parse_spectrum_csv(skewed, "skewed.csv");
    ADD_FAILURE() << "a diagonal with Im S = 0.3 |Re S| at every sample was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("skewed.csv column S_im: the imaginary part of a diagonal entry has one sign"),
              std::string::npos)
        << e.what();
  }
}

TEST(SpectrumCsv, WriteThenReadIsExact) {
  SpectrumData d;
  d.m = 1;
  d.M = 3;
  d.S = Eigen::MatrixXcd::Random(1, 4);
  std::stringstream s;
  write_spectrum_csv(s, d);
  EXPECT_EQ(parse_spectrum_csv(s, "x").S, d.S);
  // The optional S_var column (the samples' noise variance) round-trips too.
  d.variance = Eigen::VectorXd::Random(4).cwiseAbs().array() + 0.5;
  std::stringstream v;
  write_spectrum_csv(v, d);
  const SpectrumData back = parse_spectrum_csv(v, "x");
  EXPECT_EQ(back.S, d.S);
  EXPECT_EQ(back.variance, d.variance);
}

void expect_error(const std::string& text, ErrorKind kind, const std::string& fragment) {
  std::istringstream s(text);
  try {
    parse_spectrum_csv(s, "bad.csv");
    FAIL() << "accepted: " << text;
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), kind) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(SpectrumCsv, NamesTheLineAndWhatIsWrong) {
  expect_error("", ErrorKind::Input, "empty file");
  expect_error("freq,S_re,S_im\n", ErrorKind::Input, "line 1");
  expect_error("omega,S_re,S_im\n0,1,0\n", ErrorKind::Input, "at least 2 samples");
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,1\n", ErrorKind::Input, "line 3");
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,nan,0\n", ErrorKind::Input, "not finite");
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,inf,0\n", ErrorKind::Input, "not finite");
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,1x,0\n", ErrorKind::Input, "not a decimal number");
  expect_error("omega,S_re,S_im\n0,1,0\n1.5,1,0\n3.141592653589793,1,0\n", ErrorKind::Grid, "uniform grid");
  expect_error("omega,S11_re,S11_im,S12_re,S12_im,S21_re,S21_im\n", ErrorKind::Input, "not m*m");
  // Review finding 19: what the message used to hide.
  expect_error("omega;S_re;S_im\n0;1;0\n", ErrorKind::Input, "the separator is ';'");
  expect_error("omega,G_re,G_im,G_var\n0.5,1,0,1\n", ErrorKind::Input, "holds a frequency response");
  expect_error("u,y\n0.5,1\n", ErrorKind::Input, "holds periodic records");
  expect_error("omega\tS_re\tS_im\n0\t1\t0\n", ErrorKind::Input, "the separator is a tab");
  expect_error("0,1,0\n3.141592653589793,1,0\n", ErrorKind::Input, "holds numbers, not the header row");
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,1,2,5\n", ErrorKind::Input, "a decimal comma?");
  // M = 4 with its last row (omega = pi) lost: named, not "line 3 is off the grid for M = 3".
  expect_error("omega,S_re,S_im\n0,1,0\n0.78539816339744828,1,0\n1.5707963267948966,1,0\n"
               "2.3561944901923448,1,0\n",
               ErrorKind::Grid, "lie on the grid pi(k-1)/M of M = 4 but end at omega = 2.35619, not pi: the last 1 row(s)");
}

// Review finding 19/32: a UTF-8 byte-order mark, quoted header cells and a
// trailing comma on every line (the style of every file in ../shared/data)
// are read as the plain file.
TEST(Csv, ReadsBomQuotesAndTrailingCommas) {
  std::istringstream plain("omega,S_re,S_im\n0,2,0\n3.141592653589793,4,0\n");
  std::istringstream styled("\xEF\xBB\xBF\"omega\",\"S_re\",\"S_im\",\r\n0,2,0,\r\n3.141592653589793,4,0,\r\n");
  EXPECT_EQ(parse_spectrum_csv(styled, "s.csv").S, parse_spectrum_csv(plain, "p.csv").S);
  int inputs = 0;
  std::istringstream rec("\xEF\xBB\xBF\"u\",\"y\",\n1,2,\n3,4,\n");
  const Eigen::MatrixXd r = parse_records_csv(rec, "r.csv", inputs);
  EXPECT_EQ(inputs, 1);
  ASSERT_EQ(r.rows(), 2);
  EXPECT_EQ(r(1, 1), 4.0);
  std::istringstream frf("\"omega\",\"G_re\",\"G_im\",\n0.5,1,0,\n1.0,2,0,\n");
  EXPECT_EQ(parse_frf_csv(frf, "f.csv", Domain::Discrete).frequencies(), 2);
  // Without a trailing comma in the header, an empty last cell is still an empty value.
  std::istringstream empty_cell("omega,S_re,S_im\n0,2,\n3.141592653589793,4,0\n");
  EXPECT_THROW(parse_spectrum_csv(empty_cell, "e.csv"), Error);
}

// An output path that names a symbolic link writes the link's target and
// keeps the link; one that names a FIFO (as /dev/null names a device) writes
// into it instead of replacing it by a renamed regular file (a user review:
// --json link.json made the link a file, --json /dev/full replaced the device).
// The FIFO's reader is opened non-blocking first, so the writer's open does not
// wait and a regression fails instead of hanging.
TEST(OutputFile, WritesThroughLinksAndSpecialFiles) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / ("fdsid_output_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path target = dir / "target.json", link = dir / "link.json";
  fs::create_symlink("target.json", link);  // relative, as ln -s writes it: a dangling link first
  require_writable_path(link.string(), "--json");
  write_text_file(link.string(), "one\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  std::ifstream t(target);
  std::string line;
  std::getline(t, line);
  EXPECT_EQ(line, "one");

  const fs::path fifo = dir / "fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  require_writable_path(fifo.string(), "--out");
  write_text_file(fifo.string(), "two\n");
  char buf[16] = {};
  EXPECT_EQ(read(reader, buf, sizeof buf - 1), 4);
  EXPECT_STREQ(buf, "two\n");
  close(reader);
  EXPECT_TRUE(fs::is_fifo(fs::status(fifo)));
  EXPECT_FALSE(fs::exists(dir / "fifo.tmp-fdsid"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fdsid
