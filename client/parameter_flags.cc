#include "client/parameter_flags.h"

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "absl/strings/str_split.h"
#include "common/status_macros.h"

namespace sheetmesh::client {
namespace {

namespace pb = ::google::protobuf;
using T = pb::FieldDescriptor;

// Sets one value of `f` (appends for repeated fields) from `text`.
absl::Status SetOne(pb::Message* m, const T* f, absl::string_view text, const std::string& flag) {
  const pb::Reflection* r = m->GetReflection();
  const bool rep = f->is_repeated();
  auto bad = [&](absl::string_view what) {
    return absl::InvalidArgumentError(
        absl::StrCat(flag, "=", text, ": '", text, "' is not ", what));
  };
  text = absl::StripAsciiWhitespace(text);
  switch (f->cpp_type()) {
    case T::CPPTYPE_DOUBLE: {
      double d = 0;
      if (!absl::SimpleAtod(text, &d)) return bad("a number");
      rep ? r->AddDouble(m, f, d) : r->SetDouble(m, f, d);
      return absl::OkStatus();
    }
    case T::CPPTYPE_INT32: {
      int32_t i = 0;
      if (!absl::SimpleAtoi(text, &i)) return bad("an integer");
      rep ? r->AddInt32(m, f, i) : r->SetInt32(m, f, i);
      return absl::OkStatus();
    }
    case T::CPPTYPE_INT64: {
      int64_t i = 0;
      if (!absl::SimpleAtoi(text, &i)) return bad("an integer");
      rep ? r->AddInt64(m, f, i) : r->SetInt64(m, f, i);
      return absl::OkStatus();
    }
    case T::CPPTYPE_UINT64: {
      uint64_t u = 0;
      if (!absl::SimpleAtoi(text, &u)) return bad("a non-negative integer");
      rep ? r->AddUInt64(m, f, u) : r->SetUInt64(m, f, u);
      return absl::OkStatus();
    }
    case T::CPPTYPE_BOOL: {
      bool b = false;
      if (!absl::SimpleAtob(text, &b)) return bad("true or false");
      rep ? r->AddBool(m, f, b) : r->SetBool(m, f, b);
      return absl::OkStatus();
    }
    case T::CPPTYPE_STRING:
      rep ? r->AddString(m, f, std::string(text)) : r->SetString(m, f, std::string(text));
      return absl::OkStatus();
    default:
      return absl::InvalidArgumentError(absl::StrCat(flag, " cannot be given on a command line"));
  }
}

}  // namespace

absl::StatusOr<std::vector<char*>> TakeParameterFlags(int argc, char** argv,
                                                      v1::PipelineParameters* parameters,
                                                      v1::VolumeFormat* format) {
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const absl::string_view a = argv[i];
    if (a.size() < 2 || a[0] != '-' || a == "--") {
      rest.push_back(argv[i]);
      continue;
    }
    const absl::string_view body = a.substr(a[1] == '-' ? 2 : 1);
    const size_t eq = body.find('=');
    std::string name = absl::StrReplaceAll(body.substr(0, eq), {{"-", "_"}, {".", "_"}});
    if (absl::StartsWith(name, "input_")) name = name.substr(6);
    bool negated = false;
    auto find = [&](const std::string& n) -> std::pair<pb::Message*, const T*> {
      if (n == "config_json") return {nullptr, nullptr};  // --config FILE sends it
      if (const T* f = format->GetDescriptor()->FindFieldByName(n)) return {format, f};
      if (const T* f = parameters->GetDescriptor()->FindFieldByName(n)) return {parameters, f};
      return {nullptr, nullptr};
    };
    auto [message, field] = find(name);
    if (field == nullptr && absl::StartsWith(name, "no")) {
      std::tie(message, field) = find(name.substr(2));
      negated = field != nullptr && field->cpp_type() == T::CPPTYPE_BOOL && !field->is_repeated();
      if (!negated) field = nullptr;
    }
    if (field == nullptr) {
      rest.push_back(argv[i]);  // a flag of the client itself, or a mistake for absl
      continue;
    }
    const std::string flag = absl::StrCat("--", field->name());
    std::string text;
    if (negated) {
      text = "false";
    } else if (eq != absl::string_view::npos) {
      text = std::string(body.substr(eq + 1));
    } else if (field->cpp_type() == T::CPPTYPE_BOOL) {
      text = "true";
    } else if (i + 1 < argc) {
      text = argv[++i];
    } else {
      return absl::InvalidArgumentError(absl::StrCat(flag, " needs a value"));
    }
    if (!field->is_repeated()) {
      SM_RETURN_IF_ERROR(SetOne(message, field, text, flag));
      continue;
    }
    // Lists: "2,3,4"; dims also "64x64x32"; a window also "LO:HI".
    message->GetReflection()->ClearField(message, field);
    const char sep = field->name() == "dims" && absl::StrContains(text, 'x')     ? 'x'
                     : field->name() == "window" && absl::StrContains(text, ':') ? ':'
                                                                                 : ',';
    for (absl::string_view item : absl::StrSplit(text, sep, absl::SkipEmpty())) {
      SM_RETURN_IF_ERROR(SetOne(message, field, item, flag));
    }
  }
  return rest;
}

}  // namespace sheetmesh::client
