// stream-dump: print any record stream (text or JSON Lines), filter by type, export .npy.

#include <iostream>
#include <map>
#include <set>

#include "cli/command.hpp"
#include "common/atomic_file.hpp"
#include "point_clouds/pcd_file.hpp"
#include "stream/inspect.hpp"
#include "stream/npy.hpp"
#include "stream/reader.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "stream-dump";
  u.summary = "print the records of QTE record streams";
  u.description = {
      "Reads record streams (files, or standard input when FILE is '-' or absent) and prints "
      "each record: its index, byte offset, type and size, then every field with its name, "
      "dtype, shape and first values. Every record is checked (header and payload checksums, "
      "field layout) as it is read; the first damage stops the dump with one line naming the "
      "file, record index and byte offset.",
      "With --json each record becomes one JSON object per line (JSON Lines), for jq and "
      "scripts. With --npy every array is also exported as DIR/<index>.<type>.<field>.npy "
      "(index zero-padded to 6 digits) for NumPy.",
      "With --pcd every camera of the shown 'obs' and 'frame' records is also written as "
      "DIR/<index>.<camera>.pcd: the world-frame point cloud (the stored points, or points "
      "rebuilt from depth) with its colours, binary XYZRGB, organized as the image (NaN where a "
      "pixel has no return), for pcl_viewer and other PCL programs.",
  };
  u.arguments = {cli::input_files()};
  u.options = {
      {"json", "", "print JSON Lines instead of text", ""},
      {"type", "T", "show only records of type T", "", true},
      {"values", "N", "values shown per field; -1 shows all", "6"},
      {"all-values", "", "show every value (same as --values -1)", ""},
      {"npy", "DIR", "also export every field of the shown records as .npy files into DIR", ""},
      {"pcd", "DIR", "also export every camera's point cloud of the shown observations as .pcd files into DIR", ""},
      {"summary", "", "print only a count of records and bytes per type at the end", ""},
      {"max-record-bytes", "N", "treat a record payload or decompressed field larger than N bytes as damage",
       std::to_string(uint64_t(4) << 30)},
  };
  u.examples = {
      {"stream-dump demos.rec", "list every record of a file with its fields"},
      {"stream-dump --json --type obs demos.rec | jq '.fields[].name'",
       "field names of the observations"},
      {"sim-step --task reach_target < actions.rec | stream-dump --npy frames/",
       "export what the simulator emits as NumPy arrays"},
      {"stream-dump --summary --pcd clouds/ episode.rec && pcl_viewer clouds/000000.front.pcd",
       "look at the first observation's point cloud in PCL's viewer"},
  };
  u.see_also = {"qte-stream(5)", "stream-cat(1)", "stream-pack(1)"};
  return u;
}

// Stops at once when the reader of our output has gone (e.g. `stream-dump | head`).
static void flush_or_stop() {
  std::cout.flush();
  cli::check_standard_output();
}

static void run(const cli::Arguments& args) {
  const std::vector<std::string> files = args.inputs();
  const auto wanted = args.all("type");
  const std::set<std::string> types(wanted.begin(), wanted.end());
  stream::InspectOptions inspect;
  inspect.max_values = args.flag("all-values") ? -1 : args.integer("values", -1, 1000000000);
  const std::string npy_dir = args.text("npy"), pcd_dir = args.text("pcd");
  for (const std::string& dir : {npy_dir, pcd_dir})
    if (!dir.empty()) make_output_directory(dir);
  stream::ReadOptions read_options;
  if (args.integer("max-record-bytes") <= 0) throw UsageError("--max-record-bytes must be positive");
  read_options.max_record_bytes = static_cast<uint64_t>(args.integer("max-record-bytes"));

  std::map<std::string, std::pair<uint64_t, uint64_t>> totals;  // type -> (records, bytes)
  for (const std::string& file : files) {
    stream::RecordReader reader(file, read_options);
    uint64_t offset = reader.byte_offset();
    while (auto record = reader.next()) {
      const uint64_t bytes = reader.byte_offset() - offset;
      offset = reader.byte_offset();
      if (!types.empty() && !types.count(record->type())) continue;
      auto& total = totals[record->type()];
      total.first += 1;
      total.second += bytes;
      char index[16];
      std::snprintf(index, sizeof index, "%06llu", static_cast<unsigned long long>(record->position.record_index));
      if (!pcd_dir.empty() && (record->type() == "obs" || record->type() == "frame"))
        for (const auto& camera : voxels::camera_clouds(*record))
          point_clouds::write_pcd(pcd_dir + "/" + index + "." + camera.camera + ".pcd", camera);
      if (args.flag("summary")) continue;
      if (args.flag("json")) stream::print_record_json(std::cout, *record, bytes, inspect);
      else stream::print_record_text(std::cout, *record, bytes, inspect);
      if (!npy_dir.empty()) {
        for (const auto& field : record->fields())
          stream::write_npy(npy_dir + "/" + index + "." + record->type() + "." + field.name() +
                                ".npy",
                            field);
      }
      flush_or_stop();
    }
  }
  if (args.flag("summary")) {
    for (const auto& [type, total] : totals)
      std::cout << type << "\t" << total.first << " records\t" << total.second << " bytes\n";
    flush_or_stop();
  }
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
