// Fuzz target: the CSV reader of diagnose_gap (gap::readCsv). The first input byte picks a
// --columns map (names, indices, negated columns, a missing key, an unknown key, no t column with
// or without --rate), the second --skip-lines, the rest is the CSV text. Allowed outcomes: a
// recording whose stamps and data are all finite and consistent in size, or a std::exception
// with a message (the tool's main catches those).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>

#include "periodic_bias_compensation/gap/csv.h"

#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static const std::string path = "/tmp/pbc_fuzz_csv_" + std::to_string(::getpid()) + ".csv";
  pbc_fuzz::Input in(data, size);
  static const char* const kColumns[] = {
    "t=t,ax=ax,ay=ay,az=az,gx=gx,gy=gy,gz=gz",
    "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=6",
    "t=time,ax=-ax,ay=ay,az=-az,gx=gx,gy=-gy,gz=gz,temp=temp",
    "ax=1,ay=2,az=3,gx=4,gy=5,gz=6",
    "t=0,ax=1,ay=2,az=3,gx=4,gy=5",
    "t=99999999999999999999,ax=1,ay=2,az=3,gx=4,gy=5,gz=6",
    "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=6,temp=7",
    "t,ax=1",
    "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=6,wz=7",
  };
  namespace gap = periodic_bias_compensation::gap;
  gap::CsvOptions o;
  o.columns = kColumns[in.byte() % (sizeof kColumns / sizeof kColumns[0])];
  o.skip_lines = in.byte() % 3;
  o.rate = in.flag() ? 100.0 : 0.0;
  o.path = path;
  {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    const std::string text = in.rest();
    file.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
  try
  {
    const gap::Recording r = gap::readCsv(o);
    if (static_cast<std::size_t>(r.data.rows()) != r.stamp.size() || r.data.cols() != 6)
    {
      pbc_fuzz::fail("readCsv: data and stamps differ in size");
    }
    if (!r.data.allFinite())
    {
      pbc_fuzz::fail("readCsv: non-finite data value");
    }
    for (double t : r.stamp)
    {
      if (!std::isfinite(t))
      {
        pbc_fuzz::fail("readCsv: non-finite stamp");
      }
    }
    if (r.has_temperature && r.temperature.size() != r.stamp.size())
    {
      pbc_fuzz::fail("readCsv: temperature and stamps differ in size");
    }
  }
  catch (const std::exception& e)
  {
    if (std::string(e.what()).empty())
    {
      pbc_fuzz::fail("readCsv threw without a message");
    }
  }
  return 0;
}
