// Fuzz target: the YAML files a user hands to the tools: the parameter file of compensate_bag
// (--params, YamlParameterSource + readParameters, the keys of config/compensator.yaml) and the
// constant-bias calibration file (loadCalibration). Arbitrary text, written to a temporary file.
// Allowed outcomes: success, or false / std::runtime_error with a message. A parameter set that
// reads successfully must validate and must construct a Compensator.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include "fuzz_input.h"
#include "periodic_bias_compensation/core/calibration_file.h"
#include "periodic_bias_compensation/ros/parameters.h"

namespace pbc = periodic_bias_compensation;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static const std::string path = "/tmp/pbc_fuzz_params_" + std::to_string(::getpid()) + ".yaml";
  {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  std::string why;
  try
  {
    pbc::Parameters params;
    if (pbc::readParameters(pbc::YamlParameterSource(path), &params, &why))
    {
      if (!params.core.validate(nullptr) || !params.ros.validate(nullptr))
      {
        pbc_fuzz::fail("readParameters accepted parameters that do not validate");
      }
      pbc::Compensator compensator(params.core);  // must not throw
    }
    else if (why.empty())
    {
      pbc_fuzz::fail("readParameters refused without a message");
    }
  }
  catch (const std::runtime_error& e)
  {
    if (std::string(e.what()).empty())
    {
      pbc_fuzz::fail("exception without a message");
    }
  }
  why.clear();
  Eigen::Vector3d bias(0, 0, 0);
  try
  {
    if (pbc::loadCalibration(path, &bias, &why))
    {
      if (!bias.allFinite())
      {
        pbc_fuzz::fail("loadCalibration returned a non-finite bias");
      }
    }
    else if (why.empty())
    {
      pbc_fuzz::fail("loadCalibration refused without a message");
    }
  }
  catch (const std::exception& e)
  {
    // F2 (docs/reliability.md, fixed): loadCalibration threw YAML exceptions for some malformed
    // files instead of returning false with a message.
    pbc_fuzz::fail(std::string("loadCalibration threw: ") + e.what());
  }
  std::remove(path.c_str());
  return 0;
}
