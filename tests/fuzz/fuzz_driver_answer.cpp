// libFuzzer target: what robot-step reads from outside (formats/robot-spool.md): a driver's
// .done and .fault answers read as files, a judge's words, an outcomes file. The first byte
// picks the reader (0: .done, 1: .fault's text, 2: a judge command's line, 3: an outcomes file
// judged to its end), the rest is the file. Error naming the file is the expected outcome; text
// bound for an observation must come out valid UTF-8 within its limit (checked here by a decoder
// of its own). Run: make fuzz FUZZ_TARGETS=driver_answer.
#include <cstdlib>

#include "common/bounded_file.hpp"
#include "fuzz_support.hpp"
#include "robot_step/judge.hpp"
#include "robot_step/spool.hpp"

namespace {

// True when `text` is UTF-8 without ASCII control characters: decoded here, not by clean_text.
bool valid_observation_text(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) return false;
    std::size_t extra = 0;
    if ((c & 0xe0) == 0xc0) extra = 1;
    else if ((c & 0xf0) == 0xe0) extra = 2;
    else if ((c & 0xf8) == 0xf0) extra = 3;
    else if (c >= 0x80) return false;
    if (i + extra >= text.size()) return false;
    uint32_t code = extra == 0 ? c : extra == 1 ? c & 0x1f : extra == 2 ? c & 0x0f : c & 0x07;
    for (std::size_t k = 1; k <= extra; ++k) {
      const unsigned char next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xc0) != 0x80) return false;
      code = (code << 6) | (next & 0x3f);
    }
    const uint32_t least[] = {0, 0x80, 0x800, 0x10000};
    if (code < least[extra] || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff)) return false;
    i += extra + 1;
  }
  return true;
}

void require(bool condition) {
  if (!condition) std::abort();  // a finding
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace qte::robot_step;
  if (size == 0) return 0;
  const std::string& path = qte::fuzz::as_file(data + 1, size - 1);
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    switch (data[0] % 4) {
      case 0: {
        const MotionAnswer answer = parse_done(qte::read_regular_file(path, kAnswerLimitBytes, "a driver's answer"), path);
        require(answer.done && answer.degrees.allFinite() && answer.gripper >= 0 && answer.gripper <= 850);
        break;
      }
      case 1: {
        const std::string cleaned = qte::clean_text(text, kFaultTextLimitBytes);
        require(cleaned.size() <= kFaultTextLimitBytes && valid_observation_text(cleaned));
        require(qte::clean_text(cleaned, kFaultTextLimitBytes) == cleaned);  // clean text stays as it is
        break;
      }
      case 2: {
        const Verdict verdict = parse_verdict(text.substr(0, text.find('\n')), "the judge");
        require(valid_observation_text(verdict.reason) && verdict.reason.size() <= kFaultTextLimitBytes);
        break;
      }
      default: {
        const auto judge = file_judge(path);
        for (int step = 1;; ++step) {  // to the file's end: "no outcome left" is an Error
          const Verdict verdict = judge->judge({{}, step, 10, "", ""});
          require(valid_observation_text(verdict.reason) && verdict.reason.size() <= kFaultTextLimitBytes);
        }
      }
    }
  } catch (const qte::Error&) {
  }
  return 0;
}
