#include "periodic_bias_compensation/ros/parameter_reference.h"

#include <cmath>
#include <sstream>

#include "periodic_bias_compensation/ros/parameters.h"

namespace periodic_bias_compensation
{
namespace
{
/// A Markdown table cell: '|' would end it.
std::string cell(const std::string& text)
{
  std::string escaped;
  for (const char c : text)
    escaped += c == '|' ? std::string("\\|") : std::string(1, c);
  return escaped;
}

std::string code(const std::string& text)
{
  return "`" + (text.empty() ? std::string("\"\"") : text) + "`";
}

/// The accepted values: a range or the choices as code, other rules as words.
std::string accepted(const ParameterInfo& info)
{
  if (info.type == ParameterType::kInt || info.type == ParameterType::kDouble)
    return code(describeAccepted(info));
  std::string choices;
  for (const ParameterChoice& choice : info.choices)
    choices += (choices.empty() ? "" : ", ") + code(choice.value);
  return choices.empty() ? describeAccepted(info) : choices;
}

std::string markdownRow(const ParameterInfo& info, const ParameterValue& default_value)
{
  std::string description = info.description;
  for (const ParameterChoice& choice : info.choices)
    description += "; " + code(choice.value) + ": " + choice.description;
  if (!info.range_reason.empty())
    description += " (range: " + info.range_reason + ")";
  return "| " + code("~" + info.key) + " | " + toString(info.type) + " | " + code(toString(default_value)) + " | " +
         accepted(info) + " | " + cell(info.unit) + " | " + (info.reconfigurable() ? "yes" : "") + " | " +
         cell(description) + " |\n";
}

template <class Config>
std::string markdownTable(const ParameterTable<Config>& table)
{
  std::string text =
      "| parameter | type | default | accepted | unit | run time | description |\n"
      "|---|---|---|---|---|---|---|\n";
  for (const Parameter<Config>& parameter : table)
    text += markdownRow(parameter, parameter.defaultValue());
  return text;
}

/// A Python string literal.
std::string python(const std::string& text)
{
  std::string literal = "\"";
  for (const char c : text)
    literal += c == '"' || c == '\\' ? std::string("\\") + c : std::string(1, c);
  return literal + "\"";
}

std::string python(const ParameterValue& value)
{
  switch (typeOf(value))
  {
    case ParameterType::kBool:
      return std::get<bool>(value) ? "True" : "False";
    case ParameterType::kString:
      return python(std::get<std::string>(value));
    case ParameterType::kInt:
    case ParameterType::kDouble:
      break;
  }
  return toString(value);
}

std::string declaration(const Parameter<CompensatorConfig>& parameter)
{
  std::ostringstream line;
  const ParameterRange& range = parameter.range;
  const bool number = parameter.type == ParameterType::kInt || parameter.type == ParameterType::kDouble;
  if (number &&
      ((!range.min_inclusive && std::isfinite(range.min)) || (!range.max_inclusive && std::isfinite(range.max))))
    line << "# accepted " << toString(range) << ": an open bound is given as the nearest double inside it\n";
  line << "gen.add(" << python(parameter.key) << ", " << reconfigureType(parameter.type) << "_t"
       << ", 0, " << python(reconfigureDescription(parameter)) << ", " << python(parameter.defaultValue());
  // An infinite bound is dynamic_reconfigure's default (no bound): left out.
  if (number && std::isfinite(range.lowest()))
    line << ", min=" << formatNumber(range.lowest());
  if (number && std::isfinite(range.highest()))
    line << ", max=" << formatNumber(range.highest());
  if (!parameter.choices.empty())
  {
    line << ",\n        edit_method=gen.enum([";
    for (std::size_t i = 0; i < parameter.choices.size(); ++i)
    {
      const ParameterChoice& choice = parameter.choices[i];
      line << (i > 0 ? ",\n                              " : "") << "gen.const(" << python(choice.value) << ", str_t, "
           << python(choice.value) << ", " << python(choice.description) << ")";
    }
    line << "], " << python(parameter.description) << ")";
  }
  line << ")\n";
  return line.str();
}

/// Start and end (exclusive) of the text between the marker lines; false when one is missing.
bool findSection(const std::string& text, const GeneratedSection& section, std::size_t* begin, std::size_t* end)
{
  const std::string begin_line = section.begin_marker + "\n", end_line = "\n" + section.end_marker + "\n";
  const std::size_t b = text.find(begin_line);
  if (b == std::string::npos || (b > 0 && text[b - 1] != '\n'))
    return false;
  *begin = b + begin_line.size();
  const std::size_t e = text.find(end_line, *begin - 1);
  if (e == std::string::npos)
    return false;
  *end = e + 1;
  return true;
}
}  // namespace

std::string reconfigureType(ParameterType type)
{
  const char* const names[] = { "bool", "int", "double", "str" };
  return names[static_cast<int>(type)];
}

std::string reconfigureDescription(const ParameterInfo& info)
{
  return info.description + (info.unit.empty() ? "" : " [" + info.unit + "]");
}

std::string parameterReference()
{
  std::string rules;
  for (const ParameterOrder& rule : compensatorOrderRules())
    rules += (rules.empty() ? "" : ", ") + code(toString(rule));
  return "#### Estimator\n\n" + markdownTable(compensatorParameters()) + "\nBetween keys: " + rules +
         ".\n\n#### Frames, outputs, start-up\n\n" + markdownTable(rosOptionParameters());
}

std::string reconfigureDeclarations()
{
  std::string text;
  for (const Parameter<CompensatorConfig>& parameter : compensatorParameters())
    if (parameter.reconfigurable())
      text += declaration(parameter);
  return text;
}

const std::vector<GeneratedSection>& generatedSections()
{
  static const std::vector<GeneratedSection> sections = {
    { "docs/ros_api.md", "<!-- BEGIN GENERATED by parameter_docs from the parameter tables: do not edit -->",
      "<!-- END GENERATED -->", &parameterReference },
    { "cfg/Compensator.cfg", "# BEGIN GENERATED by parameter_docs from the parameter tables: do not edit",
      "# END GENERATED", &reconfigureDeclarations },
  };
  return sections;
}

bool extractSection(const std::string& text, const GeneratedSection& section, std::string* generated)
{
  std::size_t begin = 0, end = 0;
  if (!findSection(text, section, &begin, &end))
    return false;
  *generated = text.substr(begin, end - begin);
  return true;
}

bool replaceSection(const std::string& text, const GeneratedSection& section, std::string* updated)
{
  std::size_t begin = 0, end = 0;
  if (!findSection(text, section, &begin, &end))
    return false;
  *updated = text.substr(0, begin) + section.generate() + text.substr(end);
  return true;
}

}  // namespace periodic_bias_compensation
