// Every spelling of a length unit a scan file or a user writes, in metres.
#include "common/length_unit.h"

#include <gtest/gtest.h>

namespace sheetmesh {
namespace {

TEST(LengthUnitTest, EachSpellingOfAUnitIsItsLengthInMetres) {
  struct Case {
    const char* unit;
    double metres;
  };
  for (const Case& c : std::initializer_list<Case>{{"m", 1},
                                                   {"metre", 1},
                                                   {"meters", 1},
                                                   {"cm", 1e-2},
                                                   {"centimeter", 1e-2},
                                                   {"mm", 1e-3},
                                                   {"Millimetres", 1e-3},
                                                   {"um", 1e-6},
                                                   {"\xC2\xB5m", 1e-6},
                                                   {"\xCE\xBCm", 1e-6},
                                                   {"micron", 1e-6},
                                                   {"microns", 1e-6},
                                                   {"micrometer", 1e-6},
                                                   {"nm", 1e-9},
                                                   {"nanometres", 1e-9},
                                                   {"\xC3\x85", 1e-10},
                                                   {"\xE2\x84\xAB", 1e-10},
                                                   {"Angstrom", 1e-10},
                                                   {"in", 0.0254},
                                                   {"inch", 0.0254},
                                                   {"Inches", 0.0254},
                                                   {"in.", 0.0254},
                                                   {"ft", 0.3048},
                                                   {"foot", 0.3048},
                                                   {"feet", 0.3048},
                                                   {"mil", 25.4e-6},
                                                   {"mils", 25.4e-6},
                                                   {"thou", 25.4e-6},
                                                   {" mm ", 1e-3},
                                                   {"km", 1e3}}) {
    EXPECT_DOUBLE_EQ(MetresPerUnit(c.unit), c.metres) << c.unit;
  }
}

TEST(LengthUnitTest, NoLengthIsZero) {
  for (const char* unit : {"", "pixel", "pixels", "voxel", "Mm", "s", "mmm", "inchs x"}) {
    EXPECT_EQ(MetresPerUnit(unit), 0) << unit;
  }
}

}  // namespace
}  // namespace sheetmesh
