#pragma once
// The XML text of VTK files read as text, independently of VTK: the array declarations of a .vtu
// (its header, before the appended binary data) and of a .pvtu, and the pieces a .pvtu lists.
// The tests compare what the summary declares with what the pieces hold through these.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace talus::test {

/// The whole file as bytes.
inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The attributes of one XML element, by name.
using XmlAttributes = std::map<std::string, std::string>;

/// Every element <tag .../> (or <tag ...>) in `xml`, in order, as its attributes.
inline std::vector<XmlAttributes> xml_elements(const std::string& xml, const std::string& tag) {
  std::vector<XmlAttributes> out;
  const std::regex element("<" + tag + R"(\s([^>]*?)/?>)");
  const std::regex attribute(R"re(([A-Za-z_][A-Za-z0-9_]*)="([^"]*)")re");
  for (auto e = std::sregex_iterator(xml.begin(), xml.end(), element); e != std::sregex_iterator(); ++e) {
    const std::string body = (*e)[1].str();
    XmlAttributes attributes;
    for (auto a = std::sregex_iterator(body.begin(), body.end(), attribute); a != std::sregex_iterator(); ++a)
      attributes[(*a)[1].str()] = (*a)[2].str();
    out.push_back(attributes);
  }
  return out;
}

/// The text between <open ...> and </open> (empty, and a test failure, if there is none).
inline std::string xml_section(const std::string& xml, const std::string& open) {
  const auto begin = xml.find("<" + open);
  const auto end = xml.find("</" + open + ">");
  EXPECT_TRUE(begin != std::string::npos && end != std::string::npos && begin < end) << open;
  if (begin == std::string::npos || end == std::string::npos || begin >= end) return {};
  return xml.substr(begin, end - begin);
}

/// One declared data array: what a reader needs to build it before reading any value.
struct ArrayDeclaration {
  std::string type, name, components;
  std::vector<std::string> component_names;
  bool operator==(const ArrayDeclaration&) const = default;
};

inline std::ostream& operator<<(std::ostream& os, const ArrayDeclaration& a) {
  os << a.type << " " << a.name << " x" << a.components;
  for (const auto& n : a.component_names) os << " " << n;
  return os;
}

/// The declarations of the <tag> elements in `section` (NumberOfComponents defaults to 1, as
/// VTK's readers take it).
inline std::vector<ArrayDeclaration> array_declarations(const std::string& section, const std::string& tag) {
  std::vector<ArrayDeclaration> out;
  for (const XmlAttributes& a : xml_elements(section, tag)) {
    ArrayDeclaration d;
    d.type = a.count("type") ? a.at("type") : "";
    d.name = a.count("Name") ? a.at("Name") : "";
    d.components = a.count("NumberOfComponents") ? a.at("NumberOfComponents") : "1";
    for (int c = 0; a.count("ComponentName" + std::to_string(c)); ++c)
      d.component_names.push_back(a.at("ComponentName" + std::to_string(c)));
    out.push_back(d);
  }
  return out;
}

/// The XML header of a .vtu written with appended raw data: the text before <AppendedData.
inline std::string vtu_header(const std::filesystem::path& path) {
  const std::string bytes = file_bytes(path);
  return bytes.substr(0, bytes.find("<AppendedData"));
}

}  // namespace talus::test
