#!/usr/bin/python3
"""The optimiser behind `plantscale train-segmenter` (training only: nothing
Python runs on the vehicle).

The C++ command reads and checks the photographs and labels, resizes them to
the model's input size (the same code the vehicle's inference uses), and
hands them over as two NumPy arrays in a folder:
  images.npy  uint8 (N, H, W, C), C = 3 (B, G, R) or 1 (grey)
  labels.npy  uint8 (N, H, W), 0 soil, 1 crop, 2 weed
  split.json  {"train": [indices], "validation": [indices]}
This script trains a small encoder-decoder on the CPU with Debian's PyTorch
and exports it to ONNX as plain Conv / BatchNormalization / Relu / Resize /
Concat (what OpenCV 4.6's importer reads). The network takes the 8-bit pixel
values as floats (N, C, H, W) and normalises them itself; it returns class
logits (N, 3, H/2, W/2), which the C++ side upsamples to the photograph.

Progress goes to standard output as one JSON object per line; the model with
the best validation mIoU so far is what is written, also on Ctrl-C.
"""

import argparse
import json
import math
import os
import random
import signal
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

CLASSES = 3


def emit(**kw):
    print(json.dumps(kw), flush=True)


def conv_bn(cin, cout, stride=1):
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, stride=stride, padding=1, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
    )


class Normalise(nn.Module):
    """(x - mean) / std per channel, as a fixed 1x1 convolution (exports as Conv)."""

    def __init__(self, mean, std):
        super().__init__()
        c = len(mean)
        self.conv = nn.Conv2d(c, c, 1, bias=True)
        with torch.no_grad():
            self.conv.weight.zero_()
            for i in range(c):
                self.conv.weight[i, i, 0, 0] = 1.0 / std[i]
            self.conv.bias.copy_(torch.tensor([-m / s for m, s in zip(mean, std)]))
        for p in self.conv.parameters():
            p.requires_grad_(False)

    def forward(self, x):
        return self.conv(x)


def conv1(cin, cout):
    return nn.Sequential(nn.Conv2d(cin, cout, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True))


class SegNet(nn.Module):
    """A U-Net of four scales (1/2 .. 1/16), width w; output at 1/2 scale, or
    with output_stride 1 at the input's scale through one more stage of width
    w/2 whose skip is a convolution of the input itself (weeds a few pixels
    across keep their outline).

    The decoder merges each skip by concatenation and a 1x1 convolution, then
    one 3x3 convolution: most of a U-Net's cost is its full-width decoder.
    """

    def __init__(self, channels, mean, std, width=16, output_stride=2):
        super().__init__()
        w = width
        self.full = output_stride == 1
        self.norm = Normalise(mean, std)
        self.stem = conv_bn(channels, w, 2)                                          # 1/2
        self.down1 = nn.Sequential(conv_bn(w, 2 * w, 2), conv_bn(2 * w, 2 * w))     # 1/4
        self.down2 = nn.Sequential(conv_bn(2 * w, 3 * w, 2), conv_bn(3 * w, 3 * w))  # 1/8
        self.down3 = nn.Sequential(conv_bn(3 * w, 4 * w, 2), conv_bn(4 * w, 4 * w))  # 1/16
        self.up2 = nn.Sequential(conv1(4 * w + 3 * w, 3 * w), conv_bn(3 * w, 3 * w))
        self.up1 = nn.Sequential(conv1(3 * w + 2 * w, 2 * w), conv_bn(2 * w, 2 * w))
        self.up0 = nn.Sequential(conv1(2 * w + w, w), conv_bn(w, w))
        if self.full:  # a last stage at the input's resolution, its skip from the input itself
            f = max(4, w // 2)
            self.skipf = conv_bn(channels, f)
            self.upf = nn.Sequential(conv1(w + f, f), conv_bn(f, f))
            self.head = nn.Conv2d(f, CLASSES, 1)
        else:
            self.head = nn.Conv2d(w, CLASSES, 1)

    @staticmethod
    def _up(x):
        return F.interpolate(x, scale_factor=2.0, mode="nearest")

    def forward(self, x):
        x = self.norm(x)
        s0 = self.stem(x)
        s1 = self.down1(s0)
        s2 = self.down2(s1)
        s3 = self.down3(s2)
        y = self.up2(torch.cat([self._up(s3), s2], 1))
        y = self.up1(torch.cat([self._up(y), s1], 1))
        y = self.up0(torch.cat([self._up(y), s0], 1))
        if self.full:
            y = self.upf(torch.cat([self._up(y), self.skipf(x)], 1))
        return self.head(y)


def confusion(pred, truth):
    idx = truth.reshape(-1).astype(np.int64) * CLASSES + pred.reshape(-1).astype(np.int64)
    return np.bincount(idx, minlength=CLASSES * CLASSES).reshape(CLASSES, CLASSES)


def iou_from(conf):
    tp = np.diag(conf).astype(np.float64)
    denom = conf.sum(0) + conf.sum(1) - tp
    iou = np.where(denom > 0, tp / np.maximum(denom, 1), np.nan)
    return iou


def to_tensor(images):
    # (N, H, W, C) uint8 -> (N, C, H, W) float of the raw 0..255 values
    return torch.from_numpy(np.ascontiguousarray(images.transpose(0, 3, 1, 2))).float()


def predict(model, images, batch=4):
    """Class maps at full input size (nearest upsampling of the logits, as in C++)."""
    out = []
    model.eval()
    with torch.no_grad():
        for i in range(0, len(images), batch):
            logits = model(to_tensor(images[i:i + batch]))
            logits = F.interpolate(logits, size=images.shape[1:3], mode="bilinear", align_corners=False)
            out.append(logits.argmax(1).numpy().astype(np.uint8))
    return np.concatenate(out, 0) if out else np.zeros((0,) + images.shape[1:3], np.uint8)


def evaluate(model, images, labels):
    if len(images) == 0:
        return None
    pred = predict(model, images)
    conf = confusion(pred, labels)
    iou = iou_from(conf)
    return {"iou": [None if math.isnan(v) else float(v) for v in iou],
            "miou": float(np.nanmean(iou)),
            "confusion": conf.tolist()}


class Augmenter:
    """Random crops, flips, quarter turns and mild photometric changes."""

    def __init__(self, rng, crop):
        self.rng = rng
        self.crop = crop

    def __call__(self, image, label):
        h, w = label.shape
        ch, cw = min(self.crop, h), min(self.crop, w)
        y = self.rng.randint(0, h - ch)
        x = self.rng.randint(0, w - cw)
        img = image[y:y + ch, x:x + cw].astype(np.float32)
        lab = label[y:y + ch, x:x + cw]
        if self.rng.random() < 0.5:
            img, lab = img[:, ::-1], lab[:, ::-1]
        if self.rng.random() < 0.5:
            img, lab = img[::-1], lab[::-1]
        if ch == cw:
            k = self.rng.randint(0, 3)
            img, lab = np.rot90(img, k), np.rot90(lab, k)
        # brightness and contrast, and a small per-channel gain (white balance)
        gain = self.rng.uniform(0.75, 1.25)
        contrast = self.rng.uniform(0.8, 1.2)
        mean = img.mean()
        img = (img - mean) * contrast + mean * gain
        if img.shape[2] == 3:
            img = img * np.array([self.rng.uniform(0.92, 1.08) for _ in range(3)], np.float32)
        img = np.clip(img, 0, 255)
        return np.ascontiguousarray(img), np.ascontiguousarray(lab)


def class_weights(labels):
    counts = np.bincount(labels.reshape(-1), minlength=CLASSES).astype(np.float64) + 1.0
    freq = counts / counts.sum()
    w = 1.0 / np.sqrt(freq)
    return torch.tensor(w / w.mean(), dtype=torch.float32)


def dice_loss(logits, target):
    prob = logits.softmax(1)
    onehot = F.one_hot(target, CLASSES).permute(0, 3, 1, 2).float()
    inter = (prob * onehot).sum((0, 2, 3))
    total = prob.sum((0, 2, 3)) + onehot.sum((0, 2, 3))
    present = onehot.sum((0, 2, 3)) > 0
    dice = (2 * inter + 1) / (total + 1)
    return (1 - dice[present]).mean() if present.any() else logits.sum() * 0


def export_onnx(model, channels, path):
    model.eval()
    dummy = torch.zeros(1, channels, 64, 64)
    tmp = path + ".part"
    torch.onnx.export(model, dummy, tmp, input_names=["image"], output_names=["logits"],
                      opset_version=11, do_constant_folding=True,
                      dynamic_axes={"image": {2: "height", 3: "width"},
                                    "logits": {2: "height_2", 3: "width_2"}})
    os.replace(tmp, path)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True)
    p.add_argument("--out", required=True, help="the ONNX file to write")
    p.add_argument("--epochs", type=int, default=30)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--width", type=int, default=16)
    p.add_argument("--output-stride", type=int, default=2, choices=(1, 2))
    p.add_argument("--crop", type=int, default=256)
    p.add_argument("--batch", type=int, default=8)
    p.add_argument("--crops-per-image", type=int, default=4)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--lr", type=float, default=3e-3)
    p.add_argument("--max-minutes", type=float, default=0.0,
                   help="a time budget (0: none): when the epochs would not fit, the learning rate anneals by "
                        "time instead and training ends within it; the best model is kept")
    p.add_argument("--reference", help="write the model's logits on the first validation image here (.npy)")
    p.add_argument("--test-data", help="a folder like --data (all of it held out): the best model's figures on it at the end")
    a = p.parse_args()

    interrupted = {"flag": False}

    def on_sigint(_sig, _frame):
        interrupted["flag"] = True
    signal.signal(signal.SIGINT, on_sigint)
    signal.signal(signal.SIGTERM, on_sigint)

    random.seed(a.seed)
    np.random.seed(a.seed)
    torch.manual_seed(a.seed)
    torch.use_deterministic_algorithms(True)
    torch.set_num_threads(a.threads if a.threads > 0 else max(1, os.cpu_count() or 1))

    images = np.load(os.path.join(a.data, "images.npy"), mmap_mode="r")
    labels = np.load(os.path.join(a.data, "labels.npy"), mmap_mode="r")
    with open(os.path.join(a.data, "split.json")) as f:
        split = json.load(f)
    train_idx, val_idx = split["train"], split["validation"]
    channels = images.shape[3]
    tr_images, tr_labels = np.asarray(images[train_idx]), np.asarray(labels[train_idx])
    va_images, va_labels = np.asarray(images[val_idx]), np.asarray(labels[val_idx])

    pix = tr_images.reshape(-1, channels).astype(np.float64)
    mean = pix.mean(0).tolist()
    std = np.maximum(pix.std(0), 1.0).tolist()
    model = SegNet(channels, mean, std, a.width, a.output_stride)
    weights = class_weights(tr_labels)
    opt = torch.optim.AdamW([q for q in model.parameters() if q.requires_grad], lr=a.lr, weight_decay=1e-4)
    steps_per_epoch = max(1, math.ceil(len(train_idx) * a.crops_per_image / a.batch))
    total_steps = steps_per_epoch * a.epochs

    def progress(step):
        """How far the run is: by steps, or by time when the time budget binds first."""
        p = step / total_steps
        if a.max_minutes > 0:
            p = max(p, (time.time() - start) / (60.0 * a.max_minutes))
        return min(p, 1.0)

    def set_lr(p):
        # linear warm-up over the first 5 %, then a cosine down to 2 % of the peak
        lr = a.lr * (p / 0.05 if p < 0.05 else 0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * (p - 0.05) / 0.95)))
        for g in opt.param_groups:
            g["lr"] = lr
    rng = random.Random(a.seed)
    aug = Augmenter(rng, a.crop)

    best = {"miou": -1.0, "epoch": 0, "val": None}
    stopped_for_time = False
    emit(event="start", torch=torch.__version__, train=len(train_idx), validation=len(val_idx), channels=channels,
         epochs=a.epochs, steps_per_epoch=steps_per_epoch, mean=mean, std=std,
         parameters=sum(q.numel() for q in model.parameters()))
    start = time.time()
    step = 0
    for epoch in range(1, a.epochs + 1):
        model.train()
        order = [i for i in range(len(train_idx)) for _ in range(a.crops_per_image)]
        rng.shuffle(order)
        losses = []
        for s in range(steps_per_epoch):
            if interrupted["flag"] or progress(step) >= 1.0:
                break
            set_lr(progress(step))
            batch = order[s * a.batch:(s + 1) * a.batch] or [rng.randrange(len(train_idx))]
            pairs = [aug(tr_images[i], tr_labels[i]) for i in batch]
            x = torch.from_numpy(np.stack([q[0] for q in pairs]).transpose(0, 3, 1, 2).copy())
            y = torch.from_numpy(np.stack([q[1] for q in pairs]).astype(np.int64))
            logits = model(x)
            logits = F.interpolate(logits, size=y.shape[1:], mode="bilinear", align_corners=False)
            loss = F.cross_entropy(logits, y, weight=weights) + dice_loss(logits, y)
            opt.zero_grad()
            loss.backward()
            opt.step()
            step += 1
            losses.append(float(loss))
        if interrupted["flag"] and not losses:
            break
        val = evaluate(model, va_images, va_labels)
        score = val["miou"] if val else -float(np.mean(losses))
        improved = score > best["miou"]
        if improved or val is None:
            best = {"miou": score, "epoch": epoch, "val": val,
                    "state": {k: v.clone() for k, v in model.state_dict().items()}}
            export_onnx(model, channels, a.out)
            if a.reference and len(va_images):
                with torch.no_grad():
                    model.eval()
                    np.save(a.reference, model(to_tensor(va_images[:1]))[0].numpy().astype(np.float32))
        emit(event="epoch", epoch=epoch, epochs=a.epochs, loss=float(np.mean(losses)),
             validation_miou=val["miou"] if val else None, best_epoch=best["epoch"],
             seconds=round(time.time() - start, 1))
        if interrupted["flag"]:
            break
        if progress(step) >= 1.0 and epoch < a.epochs:
            emit(event="budget", epoch=epoch, seconds=round(time.time() - start, 1))
            stopped_for_time = True
            break
    test = None
    if a.test_data and best["epoch"] > 0:
        model.load_state_dict(best["state"])
        test = evaluate(model, np.load(os.path.join(a.test_data, "images.npy")),
                        np.load(os.path.join(a.test_data, "labels.npy")))
    emit(event="done", interrupted=interrupted["flag"], stopped_for_time=stopped_for_time,
         epochs_run=epoch if a.epochs else 0, best_epoch=best["epoch"], test=test,
         validation=best["val"], seconds=round(time.time() - start, 1), mean=mean, std=std,
         width=a.width, output_stride=a.output_stride, parameters=sum(q.numel() for q in model.parameters()))
    return 0 if best["epoch"] > 0 else 3


if __name__ == "__main__":
    sys.exit(main())
