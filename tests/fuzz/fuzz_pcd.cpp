// libFuzzer target: .pcd files through read_pcd (obs-pack --pcd), the bytes written to a file
// since the reader takes a path. Error naming the file is the expected outcome; a crash, a
// sanitizer report or an allocation past libFuzzer's limit (a header trusted) is a finding.
// Run: make fuzz FUZZ_TARGETS=pcd.
#include "fuzz_support.hpp"
#include "point_clouds/pcd_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)qte::point_clouds::read_pcd(qte::fuzz::as_file(data, size));
  } catch (const qte::Error&) {
  }
  return 0;
}
