"""Train the trajectory prior on `edmp-host gen-data` output and export it for `edmp-codegen`.

    python3 weights/prior/train.py --data data.npy --out weights/prior

writes `prior.safetensors` (float32, EMA weights), `prior.json` (everything inference needs),
`loss.png` (training and held-out loss) and `train_log.json` (the run: command, seeds, timing).
Recipe (the original implementation, vishal-2000/EDMP; deviations marked): epsilon prediction, MSE, t uniform
in 1..255, start and goal written into x_t; Adam. Deviations: lr 1e-3 with cosine decay and a
batch of 256 instead of lr 1e-4 at 2048 (a CPU budget, not a GPU one), an EMA of the weights
(0.999), and the loss over the 48 interior waypoints only (the two inpainted columns carry noise the
network cannot see, and the sampler overwrites them anyway).
"""

import argparse
import json
import math
import os
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from model import HORIZON, T, BETA_MAX, TemporalUNet, schedule  # noqa: E402
from shards import load_data  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True, help="(N, 50, J) float32 .npy from edmp-host gen-data (J: the arm's joints), or a folder of shards from shards.py")
    ap.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--dims", default="16,32,64")
    ap.add_argument("--no-top-skip", action="store_true", help="leave the full-resolution skip unused, as the original")
    ap.add_argument("--steps", type=int, default=24000)
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--ema", type=float, default=0.999)
    ap.add_argument("--holdout", type=int, default=2000, help="last N trajectories: held-out loss")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=0, help="torch threads (0: torch's default)")
    ap.add_argument("--init", help="a folder with a prior.safetensors of the same shape: train on from its weights")
    args = ap.parse_args()

    torch.manual_seed(args.seed)
    np.random.seed(args.seed)
    if args.threads:
        torch.set_num_threads(args.threads)
    device = "cuda" if torch.cuda.is_available() else "cpu"

    data = load_data(args.data)
    if data.ndim != 3 or data.shape[1] != HORIZON or data.shape[2] < 1:
        sys.exit(f"{args.data}: expected (N, {HORIZON}, J), got {data.shape}")
    joints = data.shape[2]
    x_all = torch.from_numpy(np.ascontiguousarray(data.transpose(0, 2, 1))).float().to(device)
    train, held = x_all[: -args.holdout], x_all[-args.holdout :]

    dims = tuple(int(d) for d in args.dims.split(","))
    model = TemporalUNet(dims, top_skip=not args.no_top_skip, joints=joints).to(device)
    ema = TemporalUNet(dims, top_skip=not args.no_top_skip, joints=joints).to(device)
    if args.init:
        from safetensors.torch import load_file

        model.load_state_dict(load_file(os.path.join(args.init, "prior.safetensors")))
        # Read now: --out may be the same folder, and the first export overwrites it.
        with open(os.path.join(args.init, "train_log.json")) as f:
            before = json.load(f)
        args.init_log = {k: before.get(k) for k in ("command", "steps", "elapsed_s", "held_out_loss", "init")}
    ema.load_state_dict(model.state_dict())
    for p in ema.parameters():
        p.requires_grad_(False)
    params = sum(p.numel() for p in model.parameters())
    print(f"dims {dims}: {params} parameters, {model.macs()} MAC per trajectory per step; "
          f"{train.shape[0]} training, {held.shape[0]} held-out trajectories on {device}")

    _, _, alpha_bars = schedule()
    sqrt_ab = alpha_bars.sqrt().float().to(device)
    sqrt_1mab = (1.0 - alpha_bars).sqrt().float().to(device)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    sched = torch.optim.lr_scheduler.LambdaLR(
        opt, lambda s: 0.01 + 0.99 * 0.5 * (1 + math.cos(math.pi * min(s, args.steps) / args.steps))
    )

    def loss_of(net, x0, gen=None):
        b = x0.shape[0]
        t = torch.randint(1, T + 1, (b,), device=device, generator=gen)
        eps = torch.randn(x0.shape, device=device, generator=gen)
        xt = sqrt_ab[t - 1, None, None] * x0 + sqrt_1mab[t - 1, None, None] * eps
        xt[:, :, 0] = x0[:, :, 0]
        xt[:, :, -1] = x0[:, :, -1]
        pred = net(xt, t)
        return ((pred - eps)[:, :, 1:-1] ** 2).mean()

    def held_loss():
        gen = torch.Generator(device=device).manual_seed(12345)
        with torch.no_grad():
            return sum(loss_of(ema, held[i : i + 500], gen).item() for i in range(0, held.shape[0], 500)) / math.ceil(
                held.shape[0] / 500
            )

    from tqdm import tqdm

    log = {"step": [], "train": [], "held_step": [], "held": []}
    start = time.time()
    running = None
    bar = tqdm(range(1, args.steps + 1), desc="training", unit="step", smoothing=0.05)
    for step in bar:
        idx = torch.randint(0, train.shape[0], (args.batch,), device=device)
        loss = loss_of(model, train[idx])
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        sched.step()
        with torch.no_grad():
            for pe, pm in zip(ema.parameters(), model.parameters()):
                pe.mul_(args.ema).add_(pm, alpha=1 - args.ema)
            for be, bm in zip(ema.buffers(), model.buffers()):
                be.copy_(bm)
        running = loss.item() if running is None else 0.98 * running + 0.02 * loss.item()
        if step % 50 == 0:
            log["step"].append(step)
            log["train"].append(running)
        if step % 1000 == 0 or step == args.steps:
            h = held_loss()
            log["held_step"].append(step)
            log["held"].append(h)
            bar.set_postfix(loss=f"{running:.4f}", held=f"{h:.4f}")
            export(ema, args, log, time.time() - start, params, data.shape[0])
    elapsed = time.time() - start
    export(ema, args, log, elapsed, params, data.shape[0])
    print(f"trained {args.steps} steps in {elapsed / 60:.1f} min; held-out loss {log['held'][-1]:.5f}")


def export(ema, args, log, elapsed, params, n):
    from safetensors.torch import save_file

    os.makedirs(args.out, exist_ok=True)
    state = {k: v.detach().cpu().contiguous() for k, v in ema.state_dict().items()}
    save_file(state, os.path.join(args.out, "prior.safetensors"))
    betas, _, _ = schedule()
    config = ema.config()
    config.update(
        {
            "format": "edmp-prior/1",
            "prediction": "epsilon",
            "steps": T,
            "beta_schedule": {"kind": "linear", "beta_max": BETA_MAX, "beta_t": "beta_max * t / steps, t = 1..steps"},
            "normalization": "none: raw joint angles in radians",
            "layout": "channels first: (batch, joints, horizon)",
            "inpainting": "columns 0 and horizon-1 hold start and goal in x_t",
            "padding": "none: lengths 50 -> 25 -> 13 by stride-2 convs (k=3, pad 1); transposed convs "
            "(k=4, stride 2, pad 1) give 26 -> crop to 25 and 50",
            "parameters": params,
            "macs_per_trajectory": ema.macs(),
        }
    )
    with open(os.path.join(args.out, "prior.json"), "w") as f:
        json.dump(config, f, indent=2)
        f.write("\n")
    with open(os.path.join(args.out, "train_log.json"), "w") as f:
        json.dump(
            {
                "command": "python3 " + " ".join(sys.argv),
                "data_trajectories": n,
                "seed": args.seed,
                "steps": args.steps,
                "batch": args.batch,
                "lr": args.lr,
                "ema": args.ema,
                "elapsed_s": round(elapsed, 1),
                "torch": torch.__version__,
                "threads": torch.get_num_threads(),
                "device": "cuda" if torch.cuda.is_available() else "cpu",
                "held_out_loss": log["held"][-1] if log["held"] else None,
                "init": getattr(args, "init_log", None),
                "loss": log,
            },
            f,
        )
        f.write("\n")
    plot(log, os.path.join(args.out, "loss.png"))


def plot(log, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    ax.plot(log["step"], log["train"], label="training (running mean)")
    ax.plot(log["held_step"], log["held"], "o-", label="held-out (EMA weights)")
    ax.set_yscale("log")
    ax.set_xlabel("step (batch 256)")
    ax.set_ylabel("MSE of epsilon, interior waypoints")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


if __name__ == "__main__":
    main()
