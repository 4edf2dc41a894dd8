#pragma once
// The text of an SVG written by PLplot's svg driver (plot/, --plot): its
// characters are numeric entities (&#x4d; ...) inside <tspan> elements.
// Decoded to ASCII ('?' for anything else) so that tests can look for labels.
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace fdsid::testing {

inline std::string svg_text_of(const std::string& svg) {
  std::string out;
  const std::regex entity("&#x([0-9a-fA-F]+);");
  for (std::sregex_iterator it(svg.begin(), svg.end(), entity), end; it != end; ++it) {
    const unsigned long c = std::stoul((*it)[1].str(), nullptr, 16);
    out += c < 128 ? static_cast<char>(c) : '?';
  }
  return out;
}

inline std::string svg_file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return svg_text_of(s.str());
}

}  // namespace fdsid::testing
