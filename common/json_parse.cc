#include "common/json_parse.h"

#include <vector>

#include "absl/strings/str_cat.h"
#include "common/excerpt.h"

namespace sheetmesh {
namespace {

using Json = nlohmann::json;

// Follows the key path through a document, and keeps where and why parsing stopped.
class PathOfError : public nlohmann::json_sax<Json> {
 public:
  bool null() override { return Value(); }
  bool boolean(bool) override { return Value(); }
  bool number_integer(number_integer_t) override { return Value(); }
  bool number_unsigned(number_unsigned_t) override { return Value(); }
  bool number_float(number_float_t, const string_t&) override { return Value(); }
  bool string(string_t&) override { return Value(); }
  bool binary(binary_t&) override { return Value(); }
  bool start_object(std::size_t) override {
    frames_.push_back({true, "", 0});
    return true;
  }
  bool key(string_t& k) override {
    frames_.back().key = k;
    return true;
  }
  bool end_object() override {
    frames_.pop_back();
    return Value();
  }
  bool start_array(std::size_t) override {
    frames_.push_back({false, "", 0});
    return true;
  }
  bool end_array() override {
    frames_.pop_back();
    return Value();
  }
  bool parse_error(std::size_t position, const std::string& token,
                   const nlohmann::detail::exception& e) override {
    position_ = position;
    token_ = token;
    out_of_range_ = e.id == 406;  // a number beyond a double
    what_ = e.what();
    return false;
  }

  std::string Path() const {
    std::string path;
    for (const Frame& f : frames_) {
      if (f.object) {
        absl::StrAppend(&path, path.empty() ? "" : ".", f.key);
      } else {
        absl::StrAppend(&path, "[", f.index, "]");
      }
    }
    return path;
  }
  std::string Message(absl::string_view source) const {
    const std::string path = Path();
    const std::string where = path.empty() ? "" : absl::StrCat("'", Excerpt(path, 120), "' = ");
    if (out_of_range_) {
      return absl::StrCat(source, ": ", where, Excerpt(token_, 60),
                          " is beyond the range of a number (at most 1.8e308 in magnitude)");
    }
    return absl::StrCat(source, ": not valid JSON",
                        path.empty() ? "" : absl::StrCat(" at '", Excerpt(path, 120), "'"),
                        " (byte ", position_, "): ", Excerpt(what_));
  }

 private:
  struct Frame {
    bool object;
    std::string key;
    size_t index;
  };
  bool Value() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
    return true;
  }

  std::vector<Frame> frames_;
  size_t position_ = 0;
  std::string token_, what_;
  bool out_of_range_ = false;
};

}  // namespace

absl::StatusOr<nlohmann::json> ParseJson(absl::string_view text, absl::string_view source) {
  Json root = Json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (!root.is_discarded()) return root;
  PathOfError sax;
  Json::sax_parse(text.begin(), text.end(), &sax);
  return absl::InvalidArgumentError(sax.Message(source));
}

}  // namespace sheetmesh
