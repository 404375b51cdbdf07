#include "common/length_unit.h"

#include <array>
#include <cctype>
#include <string>

namespace sheetmesh {
namespace {

struct Unit {
  std::string_view name;
  double metres;
};

// Symbols match as written (mm is not Mm); names in any case, singular or plural.
constexpr std::array<Unit, 12> kSymbols = {{{"km", 1e3},
                                            {"m", 1},
                                            {"dm", 1e-1},
                                            {"cm", 1e-2},
                                            {"mm", 1e-3},
                                            {"um", 1e-6},
                                            {"\xC2\xB5m", 1e-6},  // micro sign
                                            {"\xCE\xBCm", 1e-6},  // Greek small mu
                                            {"nm", 1e-9},
                                            {"pm", 1e-12},
                                            {"\xC3\x85", 1e-10},        // Å, the letter
                                            {"\xE2\x84\xAB", 1e-10}}};  // Å, the sign
constexpr std::array<Unit, 16> kNames = {{{"kilometre", 1e3},
                                          {"metre", 1},
                                          {"decimetre", 1e-1},
                                          {"centimetre", 1e-2},
                                          {"millimetre", 1e-3},
                                          {"micrometre", 1e-6},
                                          {"micron", 1e-6},
                                          {"nanometre", 1e-9},
                                          {"picometre", 1e-12},
                                          {"angstrom", 1e-10},
                                          {"inch", 0.0254},
                                          {"in", 0.0254},
                                          {"foot", 0.3048},
                                          {"ft", 0.3048},
                                          {"yard", 0.9144},
                                          {"mil", 25.4e-6}}};

}  // namespace

double MetresPerUnit(std::string_view unit) {
  while (!unit.empty() && std::isspace(static_cast<unsigned char>(unit.front())))
    unit.remove_prefix(1);
  while (!unit.empty() && std::isspace(static_cast<unsigned char>(unit.back())))
    unit.remove_suffix(1);
  if (!unit.empty() && unit.back() == '.') unit.remove_suffix(1);  // "in.", "ft."
  for (const Unit& u : kSymbols)
    if (unit == u.name) return u.metres;
  std::string name(unit);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // American spellings and plurals: meter(s), inches, feet, microns, mils, thou.
  if (name == "feet") return 0.3048;
  if (name == "inches") return 0.0254;
  if (name == "thou") return 25.4e-6;
  if (name == "yd") return 0.9144;
  for (std::string_view us : {"meter", "meters"}) {
    if (name.size() >= us.size() && name.compare(name.size() - us.size(), us.size(), us) == 0) {
      name.replace(name.size() - us.size(), 5, "metre");
    }
  }
  std::string_view n = name;
  for (const Unit& u : kNames) {
    if (n == u.name) return u.metres;
    if (n.size() == u.name.size() + 1 && n.back() == 's' && n.substr(0, u.name.size()) == u.name)
      return u.metres;
  }
  return 0;
}

}  // namespace sheetmesh
