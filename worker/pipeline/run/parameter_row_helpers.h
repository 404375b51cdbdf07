// Internal to the parameter table (parameter_table.cc): the ways a row binds to its
// member of PipelineOptions, so that a row reads as one line of the table.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROW_HELPERS_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROW_HELPERS_H_

#include <algorithm>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "worker/pipeline/run/parameter_rows.h"

namespace sheetmesh::parameter_rows {

// The member a row reads and writes: SM_MEMBER(extraction.separation.radius_voxels).
#define SM_MEMBER(path) \
  [](PipelineOptions & o) -> auto& { return o.path; }

template <class Ref>
using MemberOf = std::remove_reference_t<std::invoke_result_t<Ref, PipelineOptions&>>;

template <class Ref>
auto& Read(const Ref& ref, const PipelineOptions& o) {
  return ref(const_cast<PipelineOptions&>(o));
}

inline ParamRow Row(std::string key, ParamType type, const char* range, std::string unit,
                    std::string doc) {
  ParamRow r;
  r.spec.key = std::move(key);
  r.spec.type = type;
  if (range != nullptr) r.spec.range = ParamRange::Parse(range);
  r.spec.unit = std::move(unit);
  r.spec.doc = std::move(doc);
  return r;
}

template <class Ref>
inline ParamRow Number(std::string key, Ref ref, const char* range, std::string unit,
                       std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kNumber, range, std::move(unit), std::move(doc));
  r.get = [ref](const PipelineOptions& o) -> std::optional<ParamValue> {
    return ParamValue(static_cast<double>(Read(ref, o)));
  };
  r.set = [ref](const ParamValue& v, PipelineOptions& o) {
    ref(o) = static_cast<MemberOf<Ref>>(std::get<double>(v));
  };
  return r;
}

template <class Ref>
inline ParamRow Integer(std::string key, Ref ref, const char* range, std::string unit,
                        std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kInteger, range, std::move(unit), std::move(doc));
  r.get = [ref](const PipelineOptions& o) -> std::optional<ParamValue> {
    return ParamValue(static_cast<int64_t>(Read(ref, o)));
  };
  r.set = [ref](const ParamValue& v, PipelineOptions& o) {
    ref(o) = static_cast<MemberOf<Ref>>(std::get<int64_t>(v));
  };
  return r;
}

template <class Ref>
inline ParamRow Bool(std::string key, Ref ref, std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kBool, nullptr, "", std::move(doc));
  r.get = [ref](const PipelineOptions& o) -> std::optional<ParamValue> {
    return ParamValue(static_cast<bool>(Read(ref, o)));
  };
  r.set = [ref](const ParamValue& v, PipelineOptions& o) { ref(o) = std::get<bool>(v); };
  return r;
}

template <class Ref>
inline ParamRow Text(std::string key, Ref ref, std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kText, nullptr, "", std::move(doc));
  r.get = [ref](const PipelineOptions& o) -> std::optional<ParamValue> {
    return ParamValue(Read(ref, o));
  };
  r.set = [ref](const ParamValue& v, PipelineOptions& o) { ref(o) = std::get<std::string>(v); };
  return r;
}

// A member of enum (or string) type E, spelt by `choices`.
template <class Ref, class E = MemberOf<Ref>>
inline ParamRow Choice(std::string key, Ref ref, std::vector<std::pair<std::string, E>> choices,
                       std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kChoice, nullptr, "", std::move(doc));
  for (const auto& [name, _] : choices) r.spec.choices.push_back(name);
  r.get = [ref, choices](const PipelineOptions& o) -> std::optional<ParamValue> {
    for (const auto& [name, value] : choices) {
      if (Read(ref, o) == value) return ParamValue(name);
    }
    return std::nullopt;
  };
  r.set = [ref, choices](const ParamValue& v, PipelineOptions& o) {
    for (const auto& [name, value] : choices) {
      if (std::get<std::string>(v) == name) ref(o) = value;
    }
  };
  return r;
}

// Output files: a list of names, each one a bool member.
inline ParamRow Formats(std::string key,
                        std::vector<std::pair<std::string, bool OutputOptions::*>> files,
                        std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kChoices, nullptr, "", std::move(doc));
  r.spec.allow_empty = true;
  for (const auto& [name, _] : files) r.spec.choices.push_back(name);
  r.spec.max_count = static_cast<int>(files.size());
  r.get = [files](const PipelineOptions& o) -> std::optional<ParamValue> {
    std::vector<std::string> on;
    for (const auto& [name, member] : files) {
      if (o.output.*member) on.push_back(name);
    }
    return ParamValue(on);
  };
  r.set = [files](const ParamValue& v, PipelineOptions& o) {
    const auto& on = std::get<std::vector<std::string>>(v);
    for (const auto& [name, member] : files) {
      o.output.*member = std::find(on.begin(), on.end(), name) != on.end();
    }
  };
  return r;
}

// An optional input override of three numbers (spacing, origin).
inline ParamRow Triple(std::string key, std::optional<Vec3> OpenOptions::*member, const char* range,
                       std::string unit, std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kNumbers, range, std::move(unit), std::move(doc));
  r.spec.count = 3;
  r.get = [member](const PipelineOptions& o) -> std::optional<ParamValue> {
    const std::optional<Vec3>& v = o.input.open.*member;
    if (!v) return std::nullopt;
    return ParamValue(std::vector<double>{v->x, v->y, v->z});
  };
  r.set = [member](const ParamValue& v, PipelineOptions& o) {
    const auto& x = std::get<std::vector<double>>(v);
    o.input.open.*member = Vec3(x[0], x[1], x[2]);
  };
  return r;
}

// Sheet-phase values (input.labels, input.mask_labels).
inline ParamRow Labels(std::string key, PhaseSelection SheetInput::*member, std::string doc) {
  ParamRow r = Row(std::move(key), ParamType::kNumbers, "[-1e300, 1e300]", "", std::move(doc));
  r.spec.max_count = 256;  // the values of a label image
  r.get = [member](const PipelineOptions& o) -> std::optional<ParamValue> {
    const PhaseSelection& s = o.input.*member;
    if (s.mode != PhaseSelection::Mode::kLabels) return std::nullopt;
    return ParamValue(s.labels);
  };
  r.set = [member](const ParamValue& v, PipelineOptions& o) {
    o.input.*member = PhaseSelection::Labels(std::get<std::vector<double>>(v));
  };
  return r;
}

inline ParamRow Local(ParamRow r) {
  r.spec.scope = ParamScope::kLocal;
  return r;
}

inline ParamRow Exclusive(ParamRow r, std::string group) {
  r.spec.exclusive = std::move(group);
  return r;
}

}  // namespace sheetmesh::parameter_rows

namespace sheetmesh::parameter_rows {

// Parts of the table defined in parameter_table_volume.cc.
std::vector<ParamRow> VolumeMeshRows();
std::vector<ParamRow> FlowRows();
std::vector<ParamRow> OutputRows();

}  // namespace sheetmesh::parameter_rows

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROW_HELPERS_H_
