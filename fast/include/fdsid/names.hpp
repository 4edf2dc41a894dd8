#pragma once
/// The names of an enumeration's values: one table per enumeration, in the
/// order messages list them. to_string, the CLI's choices and the readers of
/// JSON fields all use it, so each name is spelt once and every refusal lists
/// the same names.
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fdsid {

template <class E>
using NameTable = std::vector<std::pair<std::string, E>>;

/// The value named `name`, or nothing.
template <class E>
std::optional<E> from_name(const NameTable<E>& names, const std::string& name) {
  for (const auto& [n, e] : names)
    if (n == name) return e;
  return std::nullopt;
}

/// The name of `value` ("" when the table lacks it).
template <class E>
const char* name_of(const NameTable<E>& names, E value) {
  for (const auto& [n, e] : names)
    if (e == value) return n.c_str();
  return "";
}

/// The names as a sentence lists them: "a", "a or b", "a, b or c"; each
/// between `quote`s when given (a JSON field's values: "\"a\" or \"b\"").
template <class E>
std::string name_list(const NameTable<E>& names, const std::string& quote = "") {
  std::string list;
  for (size_t i = 0; i < names.size(); ++i)
    list += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + quote + names[i].first + quote;
  return list;
}

}  // namespace fdsid
