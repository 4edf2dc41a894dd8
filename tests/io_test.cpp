// Model JSON and spectrum CSV readers of the contracts.
#include <gtest/gtest.h>

#include <sstream>

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
  const char* bad[] = {
      R"({"A":[[1]],"B":[[1]],"C":[[1]]})",                         // no D
      R"({"A":[[1,2]],"B":[[1]],"C":[[1]],"D":[[1]]})",             // A not square
      R"({"A":[["x"]],"B":[[1]],"C":[[1]],"D":[[1]]})",             // not a number
      R"({"A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1,2]]})",           // D shape
      R"({"domain":"hybrid","A":[[0.5]],"B":[[1]],"C":[[1]],"D":[[1]]})",
      R"([1,2])"};
  for (const char* text : bad) EXPECT_THROW(model_from_json(nlohmann::json::parse(text), "m.json"), Error) << text;
}

TEST(SpectrumCsv, ReadsScalarAndMimoLayouts) {
  std::istringstream s1("omega,S_re,S_im\n0,2,0\n1.5707963267948966,3,0.5\n3.141592653589793,4,0\n");
  const SpectrumData d1 = parse_spectrum_csv(s1, "s.csv");
  EXPECT_EQ(d1.m, 1);
  EXPECT_EQ(d1.M, 2);
  EXPECT_EQ(d1.at(0, 0, 1), cplx(3, 0.5));

  std::istringstream s2(
      "omega,S11_re,S11_im,S12_re,S12_im,S21_re,S21_im,S22_re,S22_im\n"
      "0,1,0,2,0,3,0,4,0\n3.141592653589793,5,0,6,0,7,0,8,0\n");
  const SpectrumData d2 = parse_spectrum_csv(s2, "s.csv");
  EXPECT_EQ(d2.m, 2);
  EXPECT_EQ(d2.at(0, 1, 0), cplx(2, 0));  // S12: row 1, column 2
  EXPECT_EQ(d2.at(1, 0, 1), cplx(7, 0));  // S21
}

TEST(SpectrumCsv, WriteThenReadIsExact) {
  SpectrumData d;
  d.m = 1;
  d.M = 3;
  d.S = Eigen::MatrixXcd::Random(1, 4);
  std::stringstream s;
  write_spectrum_csv(s, d);
  EXPECT_EQ(parse_spectrum_csv(s, "x").S, d.S);
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
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,1x,0\n", ErrorKind::Input, "not a number");
  expect_error("omega,S_re,S_im\n0,1,0\n1.5,1,0\n3.141592653589793,1,0\n", ErrorKind::Grid, "uniform grid");
  expect_error("omega,S11_re,S11_im,S12_re,S12_im,S21_re,S21_im\n", ErrorKind::Input, "not m*m");
}

}  // namespace
}  // namespace fdsid
