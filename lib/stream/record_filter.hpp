// stream-cat's selection of records as a stage: by type (kept, dropped), by field value
// (NAME=VALUE: a scalar field equal to the number VALUE, or a text field equal to VALUE), and a
// count after which it wants no more input.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "stream/stage.hpp"

namespace qte::stream {

struct RecordSelection {
  std::set<std::string> keep_types;  // empty: every type
  std::set<std::string> drop_types;
  std::vector<std::pair<std::string, std::string>> fields_equal;  // every one must hold
  int64_t head = -1;                                               // records passed on; -1: no limit
};

// True when `record` has a field `name` that is text equal to `value`, or one number equal to
// the number `value` (a VALUE that is no number matches no numeric field).
bool field_equals(const Record& record, const std::string& name, const std::string& value);

class RecordFilter : public Stage {
 public:
  explicit RecordFilter(RecordSelection selection) : selection_(std::move(selection)) {}
  void handle(const Record& record, const Emit& emit) override;
  bool done() const override { return selection_.head >= 0 && passed_ >= selection_.head; }

 private:
  RecordSelection selection_;
  int64_t passed_ = 0;
};

}  // namespace qte::stream
