#!/usr/bin/env python3
"""Checks our `arm` network against the PyTorch reference (torch_qattention_ref.py): loads the
weights bench_nets wrote into the reference's Net by name, checks that the same seed draws the
same initial weights, compares the forward outputs on the same batch, takes one Adam step with
the same loss, and compares the weights and Adam moments.

    bench_nets --export DIR
    /usr/bin/python3 torch_reference_step.py DIR path/to/torch_qattention_ref.py

Exits 1 when anything differs beyond float32 rounding."""
import importlib.util
import pathlib
import sys

import numpy as np
import torch

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "lib" / "python"))
from qte_stream import read_records  # noqa: E402


def load_reference(path):
    argv, sys.argv = sys.argv, [path]  # the reference reads threads and kernels from argv
    try:
        spec = importlib.util.spec_from_file_location("torch_qattention_ref", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.argv = argv
    return module


def only_record(path):
    records = list(read_records(path))
    assert len(records) == 1, f"{path}: expected one record, got {len(records)}"
    return records[0].fields


def state_of(fields, depth):
    prefix = f"depth{depth}."
    return {k[len(prefix):]: torch.from_numpy(np.array(v)) for k, v in fields.items() if k.startswith(prefix)}


def report(what, ours, theirs, tolerance):
    difference = (ours - theirs).abs().max().item()
    scale = theirs.abs().max().item()
    good = difference <= tolerance * max(scale, 1e-12)
    print(f"{'ok  ' if good else 'FAIL'} {what}: max |ours - reference| = {difference:.3g} (max |reference| {scale:.3g})")
    return good


def main(export_dir, reference_path):
    ref = load_reference(reference_path)
    torch.set_num_threads(2)
    before = only_record(f"{export_dir}/arm_before.rec")
    after = only_record(f"{export_dir}/arm_after.rec")
    io = only_record(f"{export_dir}/arm_io.rec")
    nets = [ref.Net(False), ref.Net(True)]
    good = True
    for depth, net in enumerate(nets):
        state = state_of(before, depth)
        names = set(net.state_dict())
        assert set(state) == names, f"names differ: {sorted(set(state) ^ names)[:5]}"
        net.load_state_dict(state)
    print(f"ok   parameter names and shapes: {sum(len(n.state_dict()) for n in nets)} tensors load by name")

    # Same seed, same generator, same construction order: the same initial weights.
    torch.manual_seed(0)
    fresh = [ref.Net(False), ref.Net(True)]
    same = all(torch.equal(p, nets[i].state_dict()[k]) for i, n in enumerate(fresh) for k, p in n.state_dict().items())
    print(f"{'ok  ' if same else 'FAIL'} torch.manual_seed(0) in Python draws {'the same' if same else 'different'} initial weights")
    good = good and same

    grid = torch.from_numpy(np.array(io["grid"]))
    proprio = torch.from_numpy(np.array(io["proprio"]))
    optimiser = torch.optim.Adam([p for n in nets for p in n.parameters()], 5e-4)
    loss = 0
    for depth, net in enumerate(nets):
        q, head = net(grid, proprio)
        good &= report(f"depth {depth} translation Q", torch.from_numpy(np.array(io[f"depth{depth}.translation"])), q[:, 0], 1e-4)
        if head is not None:
            ours = torch.cat([torch.from_numpy(np.array(io[f"depth{depth}.rotation"])).flatten(1),
                              torch.from_numpy(np.array(io[f"depth{depth}.gripper"]))], 1)
            good &= report(f"depth {depth} rotation + gripper Q", ours, head, 1e-4)
        loss = loss + q.mean() + (head.mean() if head is not None else 0)
    optimiser.zero_grad()
    loss.backward()
    optimiser.step()

    # Gradients through Adam's moments (exp_avg = 0.1 g after one step), worst tensor first;
    # then the weight change itself, which is about +-lr wherever the gradient is not ~0.
    worst, flipped, total = (0.0, ""), 0, 0
    for depth, net in enumerate(nets):
        ours, initial = state_of(after, depth), state_of(before, depth)
        for name, p in net.named_parameters():
            state, field = optimiser.state[p], f"adam.depth{depth}.{name}"
            for key in ("exp_avg", "exp_avg_sq"):
                mine = torch.from_numpy(np.array(after[f"{field}.{key}"]))
                relative = ((mine - state[key]).abs().max() / state[key].abs().max().clamp(min=1e-30)).item()
                worst = max(worst, (relative, f"{field}.{key}"))
            if int(after[f"{field}.step"]) != int(state["step"]):
                print(f"FAIL {field}.step = {int(after[f'{field}.step'])}, reference {int(state['step'])}")
                good = False
            change_ours, change_ref = ours[name] - initial[name], p.detach() - initial[name]
            flipped += int(((change_ours - change_ref).abs() > 0.1 * 5e-4).sum())
            total += p.numel()
    good &= worst[0] < 1e-3
    print(f"{'ok  ' if worst[0] < 1e-3 else 'FAIL'} Adam moments after one step: worst relative difference {worst[0]:.3g} ({worst[1]})")
    good &= flipped <= total * 1e-3
    print(f"{'ok  ' if flipped <= total * 1e-3 else 'FAIL'} weights after one Adam step: {flipped} of {total} "
          f"changes differ by more than lr/10 (where the gradient is ~0 its sign is rounding)")
    print("our arm network agrees with the reference" if good else "differences found")
    return 0 if good else 1


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
