// parameter_docs: the text generated from the parameter tables (ros/parameter_reference.h).
// Prints it, or rewrites it in place in a repository's docs/ros_api.md and cfg/Compensator.cfg
// (between their marker lines; the rest of each file is left as it is).
#include <fstream>
#include <iostream>
#include <sstream>

#include "periodic_bias_compensation/ros/parameter_reference.h"
#include "periodic_bias_compensation/tools/command_line.h"

namespace pbc = periodic_bias_compensation;

namespace
{
const char* const kUsage =
    "usage: parameter_docs [--update REPOSITORY]\n"
    "  without options: prints the generated parts of docs/ros_api.md and cfg/Compensator.cfg\n"
    "  --update REPOSITORY  rewrites them in REPOSITORY (the package's source directory)\n";

bool update(const std::string& repository)
{
  for (const pbc::GeneratedSection& section : pbc::generatedSections())
  {
    const std::string path = repository + "/" + section.file;
    std::ifstream in(path);
    if (!in)
    {
      std::cerr << "parameter_docs: cannot read " << path << "\n";
      return false;
    }
    std::ostringstream text;
    text << in.rdbuf();
    std::string updated;
    if (!pbc::replaceSection(text.str(), section, &updated))
    {
      std::cerr << "parameter_docs: " << path << " lacks the line '" << section.begin_marker << "' or '"
                << section.end_marker << "'\n";
      return false;
    }
    if (updated == text.str())
      continue;
    std::ofstream(path) << updated;
    std::cout << "updated " << path << "\n";
  }
  return true;
}
}  // namespace

int main(int argc, char** argv)
{
  std::string repository;
  try
  {
    pbc::CommandLine cli(kUsage);
    cli.text("--update", &repository);
    if (!cli.parse(argc, argv))
      return 0;
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "parameter_docs: " << e.what() << "\n" << kUsage;
    return 2;
  }
  if (!repository.empty())
    return update(repository) ? 0 : 1;
  for (const pbc::GeneratedSection& section : pbc::generatedSections())
    std::cout << section.begin_marker << "  (" << section.file << ")\n"
              << section.generate() << section.end_marker << "\n";
  return 0;
}
