"""The Python PyTorch peer of `graspmap bench train`: the same MiniUNet, timed the same way.

Prints one JSON object: per-step seconds of a training step (batch 8, 128 x 128, BCE with
logits, Adam) and of an 8-rotation inference batch. bf16 uses CPU autocast and channels_last,
the reference's fast path. Run by `graspmap bench train`; not part of the product.
"""

import argparse
import json
import time

import torch
from torch import nn


class MiniUNet(nn.Module):
    """The reference MiniUNet (docs/learning.md); the state_dict names are the ones graspmap's checkpoints use."""

    def __init__(self):
        super().__init__()
        self.inc = nn.Sequential(nn.Conv2d(3, 64, 3, padding=1), nn.ReLU())
        self.down1 = nn.Sequential(nn.MaxPool2d(2), nn.Conv2d(64, 128, 3, padding=1), nn.ReLU())
        self.down2 = nn.Sequential(nn.MaxPool2d(2), nn.Conv2d(128, 256, 3, padding=1), nn.ReLU())
        self.upconv1 = nn.ConvTranspose2d(256, 128, 2, stride=2)
        self.conv1 = nn.Sequential(nn.Conv2d(256, 128, 3, padding=1), nn.ReLU())
        self.upconv2 = nn.ConvTranspose2d(128, 64, 2, stride=2)
        self.conv2 = nn.Sequential(nn.Conv2d(128, 64, 3, padding=1), nn.ReLU())
        self.outc = nn.Conv2d(64, 1, 1)

    def forward(self, x):
        x1 = self.inc(x)
        x2 = self.down1(x1)
        x3 = self.down2(x2)
        y1 = self.conv1(torch.cat([self.upconv1(x3), x2], 1))
        y2 = self.conv2(torch.cat([self.upconv2(y1), x1], 1))
        return self.outc(y2)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--threads", type=int, required=True)
    parser.add_argument("--precision", choices=["fp32", "bf16"], required=True)
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()

    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    bf16 = args.precision == "bf16"
    model = MiniUNet()
    x = torch.rand(8, 3, 128, 128)
    target = torch.zeros(8, 1, 128, 128)
    target[:, :, 64, 64] = 1.0
    if bf16:
        model = model.to(memory_format=torch.channels_last)
        x = x.contiguous(memory_format=torch.channels_last)
    optimizer = torch.optim.Adam(model.parameters(), lr=1e-3)
    loss_fn = nn.BCEWithLogitsLoss()

    def train_step():
        optimizer.zero_grad()
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=bf16):
            logits = model(x)
        loss = loss_fn(logits.float(), target)
        loss.backward()
        optimizer.step()

    def infer():
        with torch.no_grad(), torch.autocast("cpu", dtype=torch.bfloat16, enabled=bf16):
            model(x).float().sigmoid()

    def timed(step):
        for _ in range(args.warmup):
            step()
        times = []
        for _ in range(args.steps):
            start = time.perf_counter()
            step()
            times.append(time.perf_counter() - start)
        return times

    print(json.dumps({"train_step_s": timed(train_step), "infer_s": timed(infer)}))


if __name__ == "__main__":
    main()
