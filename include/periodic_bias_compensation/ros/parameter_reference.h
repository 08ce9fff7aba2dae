// Text generated from the parameter tables (compensatorParameters(), rosOptionParameters()):
// the parameter section of docs/ros_api.md and the declarations of cfg/Compensator.cfg.
// `parameter_docs --update <repository>` rewrites both; test_ros_conversions fails when either
// no longer matches the tables.
#pragma once

#include <string>
#include <vector>

#include "periodic_bias_compensation/core/parameter_table.h"

namespace periodic_bias_compensation
{
/// A part of a checked-in file generated from the tables, between two marker lines.
struct GeneratedSection
{
  std::string file;           ///< path relative to the repository root
  std::string begin_marker;   ///< whole line before the generated text
  std::string end_marker;     ///< whole line after it
  std::string (*generate)();  ///< the text between the markers
};
/// docs/ros_api.md (parameter tables) and cfg/Compensator.cfg (gen.add declarations).
const std::vector<GeneratedSection>& generatedSections();

/// The Markdown tables of every parameter (key, type, default, accepted values, unit, run time,
/// description) and the rules between them.
std::string parameterReference();
/// The gen.add(...) lines of cfg/Compensator.cfg for the run-time parameters.
std::string reconfigureDeclarations();
/// dynamic_reconfigure's name of a type: "bool", "int", "double", "str".
std::string reconfigureType(ParameterType type);
/// The description dynamic_reconfigure shows: the table's, with the unit in brackets.
std::string reconfigureDescription(const ParameterInfo& info);

/// The text between the markers of `section` in `text`; false when a marker line is missing.
bool extractSection(const std::string& text, const GeneratedSection& section, std::string* generated);
/// `text` with the part between the markers replaced by section.generate(); false when a marker
/// line is missing.
bool replaceSection(const std::string& text, const GeneratedSection& section, std::string* updated);

/// How to refresh the generated sections, for messages.
constexpr const char* kRefreshCommand = "rosrun periodic_bias_compensation parameter_docs --update <repository>";
}  // namespace periodic_bias_compensation
