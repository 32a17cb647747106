#!/usr/bin/env python3
"""The `light` Q-attention network (lib/nets/qattention_modules.cpp, LightNet) written in
PyTorch with the same layers, as the fair peer of our LibTorch step: prints the median seconds
of one training step (forward + backward + Adam, the reference's loss: mean Q plus the mean of
the head's 218 outputs) at batch 32, at depth 0 and at the last depth (with the dense head).
Run with Debian's interpreter and PyTorch (python3-torch, the libtorch we link):
    /usr/bin/python3 torch_light_ref.py [threads=2] [reps=5]"""
import sys
import time

import torch
import torch.nn as nn
import torch.nn.functional as F

THREADS = int(sys.argv[1]) if len(sys.argv) > 1 else 2
REPS = int(sys.argv[2]) if len(sys.argv) > 2 else 5
torch.set_num_threads(THREADS)
K, CHANNELS, PROPRIO, VOXELS = 16, 10, 4, 16


def leaky(x):
    return F.leaky_relu(x, 0.02)


def conv3(i, o):
    return nn.Conv3d(i, o, 3, padding=1)


def soft_argmax(t):
    p = (t.flatten(2) / 0.01).softmax(-1).view(t.shape)
    axis = [torch.linspace(-1, 1, n) for n in t.shape[2:]]
    return torch.cat([(p.sum((3, 4)) * axis[0]).sum(-1), (p.sum((2, 4)) * axis[1]).sum(-1),
                      (p.sum((2, 3)) * axis[2]).sum(-1)], 1)


def up(x):
    return F.interpolate(x, scale_factor=2, mode="trilinear", align_corners=False)


class Light(nn.Module):
    def __init__(self, last):
        super().__init__()
        self.input = conv3(CHANNELS, K)
        self.proprio = nn.Linear(PROPRIO, K)
        self.down1 = nn.Sequential(conv3(K, 2 * K), nn.LeakyReLU(0.02), conv3(2 * K, 2 * K), nn.LeakyReLU(0.02))
        self.down2 = nn.Sequential(conv3(2 * K, 4 * K), nn.LeakyReLU(0.02), conv3(4 * K, 4 * K), nn.LeakyReLU(0.02))
        self.lateral2 = nn.Conv3d(4 * K, 2 * K, 1)
        self.up1 = conv3(2 * K, 2 * K)
        self.lateral1 = nn.Conv3d(2 * K, K, 1)
        self.up0 = conv3(K, K)
        self.q = nn.Conv3d(K, 1, 1)
        self.head = nn.Sequential(nn.Linear(4 * 8 * K, 128), nn.LeakyReLU(0.02), nn.Linear(128, 128),
                                  nn.LeakyReLU(0.02), nn.Linear(128, 218)) if last else None

    def forward(self, grid, proprio):
        e0 = leaky(self.input(grid) + self.proprio(proprio)[:, :, None, None, None])
        e1 = self.down1(F.max_pool3d(e0, 3, 2, 1))
        e2 = self.down2(F.max_pool3d(e1, 3, 2, 1))
        d1 = leaky(self.up1(e1 + up(self.lateral2(e2))))
        d0 = leaky(self.up0(e0 + up(self.lateral1(d1))))
        q = self.q(d0).squeeze(1)
        if self.head is None:
            return q, None
        levels = (e0, e1, e2, d0)
        features = torch.cat([t.amax((2, 3, 4)) for t in levels] + [soft_argmax(t) for t in levels], 1)
        return q, self.head(features)


def step_seconds(last, batch=32):
    net = Light(last)
    adam = torch.optim.Adam(net.parameters(), 5e-4)
    grids, proprio = torch.randn(batch, CHANNELS, VOXELS, VOXELS, VOXELS), torch.randn(batch, PROPRIO)

    def step():
        q, head = net(grids, proprio)
        loss = q.mean() + (head.mean() if head is not None else 0)
        adam.zero_grad()
        loss.backward()
        adam.step()

    step()
    times = []
    for _ in range(REPS):
        t0 = time.perf_counter()
        step()
        times.append(time.perf_counter() - t0)
    return sorted(times)[len(times) // 2]


print(f"torch light train step b32 ({THREADS} threads): depth 0 {step_seconds(False):.4f} s, "
      f"last depth {step_seconds(True):.4f} s")
