"""Roughness of the float and the fake-quantized (int8) prior on the suite's start/goal pairs.

    python3 weights/prior/quality.py

The same problems as `edmp-host sample` (25 per family, 12 samples each), the strided sampler at
K = 10 and 25, in PyTorch: it tells what int8 costs in sample quality (the Rust int8 numbers come
from `edmp-host sample`; this script's noise draws differ from Rust's, so compare the statistics).
"""

import sys, json, glob, os, torch, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from model import schedule, fake_quantized
from parity import load
torch.set_num_threads(1)
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, '..', '..')
m = load(HERE); fq = fake_quantized(m)
_, _, ab = schedule()
probs = []
for fam in sorted(glob.glob(os.path.join(ROOT, 'benchmarks', 'problems', '*', ''))):
    for f in sorted(glob.glob(fam + '*.json'))[:25]:
        p = json.load(open(f)); probs.append((p['start'], p['goal']['joints']))
def run(net, K):
    torch.manual_seed(0)
    ars, mr, f2, l2 = [], [], [], []
    for s, g in probs:
        s = torch.tensor(s)[None, :].repeat(12, 1); g = torch.tensor(g)[None, :].repeat(12, 1)
        x = torch.randn(12, 7, 50); x[:, :, 0] = s; x[:, :, -1] = g
        ts = [255 - j * 255 // K for j in range(K)]
        with torch.no_grad():
            for j, t in enumerate(ts):
                prev = ts[j + 1] if j + 1 < K else 0
                e = net(x, torch.full((12,), t))
                abt = ab[t - 1].float(); abp = ab[prev - 1].float() if prev > 0 else torch.tensor(1.0)
                b = 1 - abt / abp
                x = (x - b / (1 - abt).sqrt() * e) / (1 - b).sqrt() + (b * torch.randn_like(x) if prev > 0 else 0)
                x[:, :, 0] = s; x[:, :, -1] = g
        d = (x[:, :, 1:] - x[:, :, :-1]).norm(dim=1)
        ars += d.mean(1).tolist(); mr += d[:, 1:-1].max(1).values.tolist(); f2 += d[:, 0].tolist(); l2 += d[:, -1].tolist()
    return [round(float(np.mean(v)), 4) for v in (ars, mr, f2, l2)]
for K in (10, 25):
    print('strided K=%d float32   AR MRESG RF2W RL2W' % K, run(m, K))
    print('strided K=%d fake-int8 AR MRESG RF2W RL2W' % K, run(fq, K))
