// stream-dump: print any record stream (text or JSON Lines), filter by type, export .npy.

#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "cli/command.hpp"
#include "common/indexed_name.hpp"
#include "common/atomic_file.hpp"
#include "point_clouds/pcd_file.hpp"
#include "stream/field_names.hpp"
#include "stream/inspect.hpp"
#include "stream/npy.hpp"
#include "stream/reader.hpp"
#include "stream/record_types.hpp"
#include "cli/stream_options.hpp"

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
      "scripts.",
      "With --npy the fields of the shown records are also exported for NumPy: one stacked array "
      "per record type and field, DIR/<type>.<field>.npy of shape [N, ...] over the N records of "
      "that type (e.g. obs.front.rgb.npy of shape [N, H, W, 3]; a str field is a 1-d bytes array "
      "|S<longest>). Row i of every file of a type comes from the same record. A field missing "
      "from some records of its type, or whose dtype or shape changes, cannot be stacked and is "
      "written per record instead, as DIR/<index>.<type>.<field>.npy (the record's index "
      "zero-padded to 6 digits); --per-record writes every field that way.",
      "With --pcd every camera of the shown 'obs' and 'frame' records is also written as "
      "DIR/<index>.<camera>.pcd: the world-frame point cloud (the stored points, or points "
      "rebuilt from depth) with its colours, binary XYZRGB, organized as the image (NaN where a "
      "pixel has no return), for pcl_viewer and other PCL programs.",
      "The exported files appear all or none: a dump stopped by damage leaves the directories "
      "as they were.",
      "With --schema no stream is read: the registry of record types and their fields "
      "(formats/record-stream.md, section 12) is printed instead, per type a line TYPE, what it "
      "holds and the programs that write it, then one line per field: a tab, then name, dtype, "
      "shape, 'optional' or 'required', and meaning, tab-separated. Names written <camera>.rgb "
      "stand for one field per camera (front.rgb, ...), depth<d>.index for one per depth "
      "(depth0.index, ...); shapes name sizes by letters ([H, W, 3]) and scalars as []. With "
      "--type only those types are printed.",
  };
  u.arguments = {cli::input_files()};
  u.options = {
      {"json", "", "print JSON Lines instead of text", ""},
      {"type", "T", "show only records of type T", "", true},
      cli::integer_option("values", "N", "values shown per field; -1 shows all",
                          cli::default_text(stream::InspectOptions{}.max_values), -1, 1000000000),
      {"all-values", "", "show every value (same as --values -1)", ""},
      {"npy", "DIR",
       "also export the fields of the shown records into DIR: one stacked .npy array per record type and field", ""},
      {"per-record", "", "with --npy, write one .npy file per record and field instead of stacked arrays", ""},
      {"pcd", "DIR", "also export every camera's point cloud of the shown observations as .pcd files into DIR", ""},
      {"summary", "", "print only a count of records and bytes per type at the end", ""},
      {"schema", "",
       "print the record types and their fields (name, dtype, shape, optional, meaning) "
       "instead of reading streams",
       ""},
      {"text", "",
       "with --npy or --pcd, print the records as well (without it those write files only; --json "
       "prints them as JSON Lines)",
       ""},
      cli::max_record_bytes_option(),
  };
  u.examples = {
      {"stream-dump demos.rec", "list every record of a file with its fields"},
      {"stream-dump --json --type obs demos.rec | jq '.fields[].name'",
       "field names of the observations"},
      {"stream-dump --type obs --npy arrays/ demos.rec && ls arrays/",
       "the observations as stacked NumPy arrays (arrays/obs.front.rgb.npy, ...)"},
      {"stream-dump --pcd clouds/ episode.rec && pcl_viewer clouds/000000.front.pcd",
       "look at the first observation's point cloud in PCL's viewer"},
      {"stream-dump --schema --type obs", "the fields an observation holds, with dtype, shape and meaning"},
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
  for (const std::string& type : types)
    if (!stream::find_record_type(type))
      throw UsageError("--type " + type + ": no such record type (the types: " + stream::record_type_names() + ")");
  if (args.flag("schema")) {
    if (!args.positional().empty()) throw UsageError("--schema reads no stream (given: " + args.positional()[0] + ")");
    for (const char* other : {"json", "values", "all-values", "npy", "per-record", "pcd", "summary", "text"})
      if (args.has(other)) throw UsageError(std::string("--schema takes no --") + other + " (only --type)");
    for (const stream::RecordType& type : stream::record_types())
      if (types.empty() || types.count(type.name)) std::cout << stream::schema_text(type);
    flush_or_stop();
    return;
  }
  stream::InspectOptions inspect;
  inspect.max_values = args.flag("all-values") ? -1 : args.integer("values");
  if (args.flag("per-record") && !args.has("npy")) throw UsageError("--per-record goes with --npy DIR");
  // The exported files appear all or none (one staging directory when both options name one).
  std::unique_ptr<OutputDirectory> npy_out, pcd_out;
  if (args.has("npy")) npy_out = std::make_unique<OutputDirectory>(args.text("npy"));
  std::error_code not_same;
  if (args.has("pcd") && !(npy_out && std::filesystem::equivalent(args.text("npy"), args.text("pcd"), not_same)))
    pcd_out = std::make_unique<OutputDirectory>(args.text("pcd"));
  OutputDirectory* pcd = pcd_out ? pcd_out.get() : args.has("pcd") ? npy_out.get() : nullptr;
  std::unique_ptr<stream::NpyExport> npy;
  if (npy_out) npy = std::make_unique<stream::NpyExport>(npy_out->staging(), args.flag("per-record"));
  const stream::ReadOptions read_options = cli::read_options_from(args);

  // Exporting is what --npy and --pcd are for: the text too only when asked for.
  const bool print_records =
      !args.flag("summary") && (args.flag("json") || args.flag("text") || (!npy_out && !args.has("pcd")));
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
      if (pcd && (record->type() == record_type::obs || record->type() == record_type::frame))
        for (const auto& camera : voxels::camera_clouds(*record))
          point_clouds::write_pcd(pcd->path(indexed_name(record->position.record_index, camera.camera + ".pcd")), camera);
      if (npy) npy->add(*record);
      if (!print_records) continue;
      if (args.flag("json")) stream::print_record_json(std::cout, *record, bytes, inspect);
      else stream::print_record_text(std::cout, *record, bytes, inspect);
      flush_or_stop();
    }
  }
  if (npy) npy->finish();
  for (OutputDirectory* out : {npy_out.get(), pcd_out.get()})
    if (out) out->commit();
  if (args.flag("summary")) {
    for (const auto& [type, total] : totals)
      std::cout << type << "\t" << total.first << " records\t" << total.second << " bytes\n";
    flush_or_stop();
  }
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
