"""Write the parity fixture the Rust int8 network is tested against.

    python3 weights/prior/parity.py --data data.npy
    python3 weights/prior/parity.py --data iiwa7.npy --weights weights/iiwa7 \
        --out tests/fixtures/prior_parity_iiwa7.json

For fixed inputs (several t; x_t made from held-out trajectories as in training, and pure noise)
it records the float model's epsilon and the fake-quantized model's (int8 weights * scale, float
activations: what edmp-core computes) to `tests/fixtures/prior_parity.json`, and prints the
int8-vs-float error.
"""

import argparse
import json
import os
import sys

import numpy as np
import torch

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from model import T, TemporalUNet, fake_quantized, is_quantized, schedule  # noqa: E402
from shards import load_data  # noqa: E402


def load(directory):
    from safetensors.torch import load_file

    with open(os.path.join(directory, "prior.json")) as f:
        config = json.load(f)
    model = TemporalUNet(tuple(config["dims"]), config["time_dim"], config["time_hidden"], config.get("top_skip", False), config.get("joints", 7))
    model.load_state_dict(load_file(os.path.join(directory, "prior.safetensors")))
    model.eval()
    return model


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, help="the gen-data .npy (or shards folder) the prior was trained on")
    ap.add_argument("--weights", default=HERE)
    ap.add_argument("--out", default=os.path.join(HERE, "..", "..", "tests", "fixtures", "prior_parity.json"))
    ap.add_argument("--seed", type=int, default=20261124)
    args = ap.parse_args()

    torch.manual_seed(args.seed)
    model = load(args.weights)
    fq = fake_quantized(model)
    data = load_data(args.data)
    _, _, alpha_bars = schedule()

    steps = [1, 2, 10, 64, 128, 200, 254, 255]
    cases = []
    # Held-out trajectories (the trainer holds out the last 2000).
    pick = np.random.default_rng(args.seed).choice(np.arange(len(data) - 2000, len(data)), len(steps), replace=False)
    for i, t in enumerate(steps):
        x0 = torch.from_numpy(np.array(data[pick[i]]).T.copy()).float()[None]
        eps = torch.randn(x0.shape)
        ab = alpha_bars[t - 1].float()
        xt = ab.sqrt() * x0 + (1 - ab).sqrt() * eps
        xt[:, :, 0], xt[:, :, -1] = x0[:, :, 0], x0[:, :, -1]
        cases.append((t, xt))
    for t in (255, 128, 3):
        xt = torch.randn(1, model.joints, 50)
        cases.append((t, xt))

    out = {"seed": args.seed, "note": f"x and eps are waypoint-major (50 x {model.joints}); regenerate with weights/prior/parity.py", "cases": []}
    worst_q, worst_scale = 0.0, 0.0
    with torch.no_grad():
        for t, xt in cases:
            tt = torch.tensor([t])
            ef = model(xt, tt)[0]
            eq = fq(xt, tt)[0]
            worst_q = max(worst_q, (eq - ef).abs().max().item())
            worst_scale = max(worst_scale, ef.abs().max().item())
            out["cases"].append(
                {
                    "t": t,
                    "x": xt[0].T.tolist(),
                    "eps_float": ef.T.tolist(),
                    "eps_fake_quant": eq.T.tolist(),
                }
            )
    rel = [
        np.abs(np.array(c["eps_fake_quant"]) - np.array(c["eps_float"])).max() / np.abs(np.array(c["eps_float"])).max()
        for c in out["cases"]
    ]
    out["int8_vs_float_max_abs"] = worst_q
    out["int8_vs_float_max_relative"] = float(max(rel))
    with open(args.out, "w") as f:
        json.dump(out, f)
        f.write("\n")
    print(f"{len(cases)} cases -> {os.path.relpath(args.out)}; int8 vs float: max |diff| {worst_q:.3e}, "
          f"max relative to the case's max |eps| {max(rel):.3e} (T = {T})")
    compare_quantization(model, data)


def per_tensor(model):
    """The alternative measured against: one symmetric scale per tensor."""
    import copy

    fq = copy.deepcopy(model)
    with torch.no_grad():
        for name, p in fq.named_parameters():
            if is_quantized(name, p):
                scale = p.abs().max() / 127.0
                p.copy_(torch.clamp(torch.round(p / scale), -127, 127) * scale)
    return fq


def compare_quantization(model, data, n=2000):
    """Held-out loss (interior epsilon MSE, t uniform) of the float model and two int8 schemes."""
    _, _, alpha_bars = schedule()
    gen = torch.Generator().manual_seed(7)
    x0 = torch.from_numpy(np.array(data[len(data) - n :]).transpose(0, 2, 1).copy()).float()
    t = torch.randint(1, T + 1, (n,), generator=gen)
    eps = torch.randn(x0.shape, generator=gen)
    ab = alpha_bars[t - 1].float()[:, None, None]
    xt = ab.sqrt() * x0 + (1 - ab).sqrt() * eps
    xt[:, :, 0], xt[:, :, -1] = x0[:, :, 0], x0[:, :, -1]
    with torch.no_grad():
        ref = model(xt, t)
        for label, net in (("float32", model), ("int8 per output channel (used)", fake_quantized(model)),
                           ("int8 per tensor", per_tensor(model))):
            out = ref if net is model else net(xt, t)
            loss = ((out - eps)[:, :, 1:-1] ** 2).mean().item()
            rms = ((out - ref) ** 2).mean().sqrt().item()
            print(f"  {label:32s} held-out loss {loss:.5f}   rms difference from float {rms:.5f}")


if __name__ == "__main__":
    main()
