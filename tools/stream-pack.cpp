// stream-pack: write one record from command-line values and .npy files.
#include "cli/command.hpp"
#include "stream/field_spec.hpp"
#include "cli/stream_options.hpp"
#include "stream/writer.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "stream-pack";
  u.summary = "write one record from values and NumPy files";
  u.description = {
      "Builds one record of type TYPE from FIELD specifications and writes it as a record "
      "stream. Several invocations concatenate naturally: { stream-pack ...; stream-pack ...; } "
      "> file.rec. This is how a shell script or a Python program that saved .npy files "
      "feeds the toolkit without linking it.",
      "A FIELD is NAME=TEXT (a str field), NAME:DTYPE=V1,V2,... (a scalar, or a 1-d array "
      "when there are several values), NAME:DTYPE[D1,D2,...]=V1,V2,... (an array of that "
      "shape, values in C order) or NAME=@FILE.npy (an array read from a NumPy file). DTYPE is "
      "one of uint8 int8 uint16 int16 uint32 int32 uint64 int64 float32 float64 (or u8 ... "
      "f64).",
  };
  u.arguments = {{"TYPE", "record type, 1-16 characters of [a-z0-9_] (e.g. reset)", false, false},
                 {"FIELD", "field specifications, see above", true, true}};
  u.options = {
      {"compress", "", "zstd-compress arrays of 256 bytes or more", ""},
  };
  u.add_options(cli::append_options());
  u.options.push_back(cli::output_file());
  u.examples = {
      {"stream-pack reset task=reach_target variation:i32=0 seed:i64=7 > reset.rec",
       "a reset record for sim-step"},
      {"stream-pack obs front.rgb=@rgb.npy front.depth=@depth.npy --compress --output obs.rec",
       "an observation from NumPy arrays, compressed on disk"},
  };
  u.see_also = {"qte-stream(5)", "stream-dump(1)", "stream-cat(1)"};
  return u;
}

static void run(const cli::Arguments& args) {
  const auto& positional = args.positional();
  stream::Record record(positional.at(0));
  for (std::size_t i = 1; i < positional.size(); ++i)
    stream::add_field_from_spec(record, positional[i]);
  if (args.flag("compress")) {
    stream::Record compressed(record.type());
    for (auto field : record.fields()) {
      field.compress = true;
      compressed.add(std::move(field));
    }
    record = std::move(compressed);
  }
  stream::RecordWriter writer(args.text("output"), cli::write_options_from(args, {}));
  writer.write(record);
  writer.close();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
