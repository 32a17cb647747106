#include "nets/checkpoint.hpp"

#include <cctype>
#include <map>
#include <set>

#include "common/error.hpp"
#include "nets/qattention_modules.hpp"
#include "stream/field_names.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

namespace qte::nets {
namespace {

using torch::optim::AdamParamState;

// Weights and buffers of one network, by the names torch gives them.
std::vector<std::pair<std::string, torch::Tensor>> named_tensors(const QAttentionModule& module) {
  std::vector<std::pair<std::string, torch::Tensor>> tensors;
  for (const auto& p : module.named_parameters()) tensors.emplace_back(p.key(), p.value());
  for (const auto& b : module.named_buffers()) tensors.emplace_back(b.key(), b.value());
  return tensors;
}

// Adam keys its per-parameter state by the parameter's TensorImpl (as torch/optim/serialize.h).
std::string adam_key(const torch::Tensor& parameter) { return c10::guts::to_string(parameter.unsafeGetTensorImpl()); }

stream::Shape shape_of(const torch::Tensor& t) { return stream::Shape(t.sizes().begin(), t.sizes().end()); }

void set_tensor(stream::Record& record, const std::string& name, const torch::Tensor& tensor) {
  const auto values = tensor.detach().to(torch::kFloat32).contiguous();
  record.set_raw(name, stream::DType::f32, shape_of(values), values.data_ptr<float>());
}

std::string config_json(const CheckpointConfig& c) {
  return std::string("{\"architecture\": \"") + architecture_name(c.net.architecture) +
         "\", \"base_channels\": " + std::to_string(c.net.base_channels) +
         ", \"voxels\": " + std::to_string(c.net.voxels) + ", \"channels\": " + std::to_string(c.net.channels) +
         ", \"proprio\": " + std::to_string(c.net.proprio) + ", \"depths\": " + std::to_string(c.depths) +
         (c.net.head_input == HeadInput::pooled ? "" : ", \"head_input\": \"" + std::string(head_input_name(c.net.head_input)) + "\"") +
         "}";
}

// The config every network of the stack shares; refuses stacks that are not one per depth.
CheckpointConfig stack_config(const std::vector<QAttentionNet>& nets) {
  if (nets.empty()) throw Error("checkpoint: no networks");
  CheckpointConfig config{nets.front().config(), static_cast<int>(nets.size()), 0};
  for (std::size_t d = 0; d < nets.size(); ++d) {
    const NetConfig& c = nets[d].config();
    const bool same = c.architecture == config.net.architecture && c.base_channels == config.net.base_channels &&
                      c.voxels == config.net.voxels && c.channels == config.net.channels &&
                      c.proprio == config.net.proprio && c.head_input == config.net.head_input;
    if (!same || c.depth != static_cast<int>(d) || c.is_last != (d + 1 == nets.size()))
      throw Error("checkpoint: network " + std::to_string(d) + " is not depth " + std::to_string(d) +
                  " of the same stack (one network per depth, same settings, the last one is_last)");
  }
  return config;
}

// `depth<digit>...` and `adam....`: the names of tensors, as opposed to config fields.
bool is_tensor_name(const std::string& name) {
  return fields::is_per_depth(name) || name.rfind(fields::adam_prefix, 0) == 0;
}

// One tensor to load: where it comes from and where it goes.
struct PendingCopy {
  const stream::Field* field;
  torch::Tensor destination;
};

}  // namespace

stream::Record checkpoint_record(const std::vector<QAttentionNet>& nets, const torch::optim::Adam* adam, int64_t step) {
  CheckpointConfig config = stack_config(nets);
  stream::Record record(record_type::checkpoint);
  record.set_string(fields::architecture, architecture_name(config.net.architecture));
  record.set_scalar<int64_t>(fields::base_channels, config.net.base_channels);
  // Written only when it is not the published input: other checkpoints keep their bytes.
  if (config.net.head_input != HeadInput::pooled)
    record.set_string(fields::head_input, head_input_name(config.net.head_input));
  record.set_scalar<int64_t>(fields::voxels, config.net.voxels);
  record.set_scalar<int64_t>(fields::channels, config.net.channels);
  record.set_scalar<int64_t>(fields::proprio, config.net.proprio);
  record.set_scalar<int64_t>(fields::depths, config.depths);
  record.set_scalar<int64_t>(fields::step, step);
  record.set_string(fields::config, config_json(config));
  for (const auto& net : nets)
    for (const auto& [name, tensor] : named_tensors(net.module()))
      set_tensor(record, fields::depth_prefix(net.config().depth) + name, tensor);
  if (adam == nullptr) return record;
  for (const auto& net : nets) {
    for (const auto& p : net.module().named_parameters()) {
      const auto found = adam->state().find(adam_key(p.value()));
      if (found == adam->state().end()) continue;  // never stepped: no state yet
      const auto& state = static_cast<const AdamParamState&>(*found->second);
      const std::string name = fields::adam_prefix + fields::depth_prefix(net.config().depth) + p.key();
      set_tensor(record, name + fields::per_parameter::exp_avg, state.exp_avg());
      set_tensor(record, name + fields::per_parameter::exp_avg_sq, state.exp_avg_sq());
      if (state.max_exp_avg_sq().defined())
        set_tensor(record, name + fields::per_parameter::max_exp_avg_sq, state.max_exp_avg_sq());
      record.set_scalar<int64_t>(name + fields::per_parameter::step, state.step());
    }
  }
  return record;
}

void save_checkpoint(const std::string& path, const std::vector<QAttentionNet>& nets, const torch::optim::Adam* adam,
                     int64_t step) {
  const stream::Record record = checkpoint_record(nets, adam, step);
  stream::RecordWriter writer(path, {stream::WriteMode::replace});
  writer.write(record);
  writer.close();
}

CheckpointConfig checkpoint_config(const stream::Record& record) {
  if (record.type() != record_type::checkpoint)
    throw StreamError(record.position, "expected a 'checkpoint' record, got '" + record.type() + "'");
  // Checked before anything is built from them: a damaged or hostile count would otherwise ask
  // for networks of terabytes.
  const auto integer = [&](const char* name, int64_t lo, int64_t hi) {
    const int64_t v = record.scalar<int64_t>(name);
    if (v < lo || v > hi)
      record.fail(name, std::to_string(lo) + ".." + std::to_string(hi) + ", got " + std::to_string(v));
    return static_cast<int>(v);
  };
  CheckpointConfig config;
  const std::string architecture = record.string(fields::architecture);
  if (architecture != "arm" && architecture != "light")
    throw StreamError(record.position, "'checkpoint' record: unknown architecture '" + architecture + "'");
  config.net.architecture = architecture_from_name(architecture);
  config.net.base_channels = integer(fields::base_channels, 1, 512);
  if (record.has(fields::head_input)) {
    const std::string input = record.string(fields::head_input);
    try {
      config.net.head_input = head_input_from_name(input);
    } catch (const Error&) {  // damage, named by the field: a StreamError
      record.fail(fields::head_input, "pooled or voxel, got '" + input + "'");
    }
  }
  config.net.voxels = integer(fields::voxels, 4, 128);
  config.net.channels = integer(fields::channels, 1, 64);
  config.net.proprio = integer(fields::proprio, 1, 64);
  config.depths = integer(fields::depths, 1, 8);
  config.net.is_last = config.depths == 1;
  config.step = record.scalar<int64_t>(fields::step);
  return config;
}

stream::Record read_online_checkpoint(const std::string& path) {
  stream::RecordReader reader(path);
  std::optional<stream::Record> online;
  while (std::optional<stream::Record> record = reader.next()) {
    if (record->type() != record_type::checkpoint || record->has(fields::role)) continue;
    if (online)
      throw StreamError(record->position, "a second online 'checkpoint' record (the first is record " +
                                              std::to_string(online->position.record_index) +
                                              "): expected one, and target networks with role 'target'");
    online = std::move(record);
  }
  if (!online)
    throw StreamError({path, reader.records_read(), reader.byte_offset()},
                      "expected a 'checkpoint' record of the online networks (without a 'role'), found none in " +
                          std::to_string(reader.records_read()) + " records");
  return std::move(*online);
}

CheckpointConfig read_checkpoint_config(const std::string& path) { return checkpoint_config(read_online_checkpoint(path)); }

int64_t load_checkpoint_record(const stream::Record& record, std::vector<QAttentionNet>& nets,
                               torch::optim::Adam* adam) {
  const CheckpointConfig want = stack_config(nets);
  const CheckpointConfig have = checkpoint_config(record);
  const auto refuse = [&](const std::string& what) {
    throw Error(record.position.describe() + ": 'checkpoint' record: " + what);
  };
  const auto compare = [&](const char* name, const std::string& in_file, const std::string& in_nets) {
    if (in_file != in_nets) refuse(std::string(name) + " is " + in_file + ", the networks have " + in_nets);
  };
  compare(fields::architecture, architecture_name(have.net.architecture), architecture_name(want.net.architecture));
  compare(fields::base_channels, std::to_string(have.net.base_channels), std::to_string(want.net.base_channels));
  compare(fields::voxels, std::to_string(have.net.voxels), std::to_string(want.net.voxels));
  compare(fields::channels, std::to_string(have.net.channels), std::to_string(want.net.channels));
  compare(fields::proprio, std::to_string(have.net.proprio), std::to_string(want.net.proprio));
  compare(fields::depths, std::to_string(have.depths), std::to_string(want.depths));

  std::set<std::string> known;  // every field a network or Adam accounts for
  const auto checked_field = [&](const std::string& name, const torch::Tensor& like) -> const stream::Field& {
    const stream::Field* field = record.find(name);
    if (field == nullptr) refuse(name + " is missing");
    if (field->dtype() != stream::DType::f32)
      refuse(name + " is " + stream::dtype_name(field->dtype()) + ", the network expects float32");
    if (field->shape() != shape_of(like))
      refuse(name + " has shape " + stream::shape_to_string(field->shape()) + ", the network expects " +
             stream::shape_to_string(shape_of(like)));
    known.insert(name);
    return *field;
  };

  std::vector<PendingCopy> copies;
  for (auto& net : nets)
    for (const auto& [name, tensor] : named_tensors(net.module()))
      copies.push_back({&checked_field(fields::depth_prefix(net.config().depth) + name, tensor), tensor});

  // Adam: per parameter, all of its state or none (a parameter that never had a gradient).
  std::map<std::string, AdamParamState> adam_states;  // by adam_key
  std::set<std::string> optimised;
  if (adam != nullptr)
    for (const auto& group : adam->param_groups())
      for (const auto& p : group.params()) optimised.insert(adam_key(p));
  for (auto& net : nets) {
    for (const auto& p : net.module().named_parameters()) {
      const std::string name = fields::adam_prefix + fields::depth_prefix(net.config().depth) + p.key();
      if (!record.has(name + fields::per_parameter::exp_avg) && !record.has(name + fields::per_parameter::exp_avg_sq) &&
          !record.has(name + fields::per_parameter::step))
        continue;
      const auto as_tensor = [](const stream::Field& f) {
        return torch::from_blob(const_cast<uint8_t*>(f.bytes()), f.shape(), torch::kFloat32).clone();
      };
      AdamParamState state;
      state.exp_avg(as_tensor(checked_field(name + fields::per_parameter::exp_avg, p.value())));
      state.exp_avg_sq(as_tensor(checked_field(name + fields::per_parameter::exp_avg_sq, p.value())));
      if (record.has(name + fields::per_parameter::max_exp_avg_sq))
        state.max_exp_avg_sq(as_tensor(checked_field(name + fields::per_parameter::max_exp_avg_sq, p.value())));
      if (!record.has(name + fields::per_parameter::step)) refuse(name + ".step is missing");
      state.step(record.scalar<int64_t>(name + fields::per_parameter::step));
      known.insert(name + fields::per_parameter::step);
      if (adam != nullptr && !optimised.count(adam_key(p.value())))
        throw Error("load_checkpoint: the optimiser does not hold parameter " +
                    fields::depth_prefix(net.config().depth) + p.key());
      adam_states.emplace(adam_key(p.value()), std::move(state));
    }
  }

  for (const auto& field : record.fields())
    if (is_tensor_name(field.name()) && !known.count(field.name()))
      refuse(field.name() + " is not a tensor of the networks");

  torch::NoGradGuard no_grad;
  for (const auto& copy : copies)
    copy.destination.copy_(
        torch::from_blob(const_cast<uint8_t*>(copy.field->bytes()), copy.field->shape(), torch::kFloat32));
  if (adam != nullptr) {
    // The optimiser's state for these networks becomes the checkpoint's: restored, or fresh.
    for (const auto& net : nets) {
      for (const auto& p : net.module().parameters()) {
        const std::string key = adam_key(p);
        const auto state = adam_states.find(key);
        if (state != adam_states.end())
          adam->state()[key] = std::make_unique<AdamParamState>(state->second);
        else
          adam->state().erase(key);
      }
    }
  }
  return have.step;
}

int64_t load_checkpoint(const std::string& path, std::vector<QAttentionNet>& nets, torch::optim::Adam* adam) {
  return load_checkpoint_record(read_online_checkpoint(path), nets, adam);
}

}  // namespace qte::nets
