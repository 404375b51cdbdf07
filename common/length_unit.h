// Length units as scan files and users spell them (ImageJ's "micron" and "inch", NRRD's
// "microns", a µ written as the micro sign or the Greek letter, Å for a synchrotron's
// nanotomography), each in metres.
#ifndef SHEETMESH_COMMON_LENGTH_UNIT_H_
#define SHEETMESH_COMMON_LENGTH_UNIT_H_

#include <string_view>

namespace sheetmesh {

// Metres in one `unit`: the SI lengths from km to pm by symbol or name (either spelling,
// singular or plural, any case but the symbols' own), micron, angstrom (Å), and the inch,
// foot, yard, mil (a thousandth of an inch) and thou. 0 for anything else: an empty unit,
// "pixel", "voxel" or one not known.
double MetresPerUnit(std::string_view unit);

// The units MetresPerUnit knows, in words for an error message.
inline constexpr char kKnownLengthUnits[] =
    "m, cm, mm, um (µm, micron), nm, Å (angstrom), in (inch), ft (foot), mil or any of "
    "their names";

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_LENGTH_UNIT_H_
