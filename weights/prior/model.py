"""The temporal 1-D UNet of EDMP, scaled down, and its diffusion schedule.

The layout follows the original implementation (vishal-2000/EDMP): Conv1d(k=5) -> GroupNorm(8)
-> Mish blocks, residual blocks with a sinusoidal time embedding, stride-2 downsampling, transposed-
conv upsampling with a crop back to the skip's length (50 -> 25 -> 13 and back), no attention.
Differences: the channel widths, and (`top_skip`, default on) the first level's full-resolution
skip, which the original computes and never uses, is concatenated before the final block.

Everything `edmp-core` needs to run this network is in `config()`; the Rust side reads the same
parameter names from the safetensors file, so keep names and shapes stable.
"""

import math

import torch
import torch.nn as nn
import torch.nn.functional as F

HORIZON = 50
JOINTS = 7  # the Panda's; other arms pass `joints`
GROUPS = 8
KERNEL = 5
T = 255
BETA_MAX = 0.02


def schedule(steps: int = T, beta_max: float = BETA_MAX):
    """The original's linear betas: beta_t = beta_max * t / steps for t = 1..steps (index t-1)."""
    betas = torch.linspace(0.0, beta_max, steps + 1, dtype=torch.float64)[1:]
    alphas = 1.0 - betas
    alpha_bars = torch.cumprod(alphas, 0)
    return betas, alphas, alpha_bars


def time_features(t: torch.Tensor, dim: int) -> torch.Tensor:
    """Sinusoidal features of the raw step index t (1..255, not normalized), as the original."""
    half = dim // 2
    freq = torch.exp(torch.arange(half, dtype=torch.float32) * -(math.log(10000.0) / (half - 1)))
    x = t.float()[:, None] * freq[None, :]
    return torch.cat([torch.sin(x), torch.cos(x)], dim=-1)


class ConvBlock(nn.Module):
    """Conv1d (same padding) -> GroupNorm -> Mish."""

    def __init__(self, cin, cout, kernel=KERNEL):
        super().__init__()
        self.conv = nn.Conv1d(cin, cout, kernel, padding=kernel // 2)
        self.norm = nn.GroupNorm(GROUPS, cout)

    def forward(self, x):
        return F.mish(self.norm(self.conv(x)))


class ResBlock(nn.Module):
    """Two conv blocks, the time embedding added after the first, a 1x1 residual if widths differ."""

    def __init__(self, cin, cout, time_dim):
        super().__init__()
        self.block0 = ConvBlock(cin, cout)
        self.block1 = ConvBlock(cout, cout)
        self.time = nn.Linear(time_dim, cout)
        self.residual = nn.Conv1d(cin, cout, 1) if cin != cout else None

    def forward(self, x, temb):
        h = self.block0(x) + self.time(F.mish(temb))[:, :, None]
        h = self.block1(h)
        return h + (self.residual(x) if self.residual is not None else x)


class TemporalUNet(nn.Module):
    """epsilon-prediction network: (B, J, 50) noisy trajectory and step t -> (B, J, 50) noise."""

    def __init__(self, dims=(16, 32, 64), time_dim=32, time_hidden=128, top_skip=True, joints=JOINTS):
        super().__init__()
        self.joints = joints
        self.dims = tuple(dims)
        self.top_skip = top_skip
        self.time_dim = time_dim
        self.time_hidden = time_hidden
        self.time_in = nn.Linear(time_dim, time_hidden)
        self.time_out = nn.Linear(time_hidden, time_dim)
        widths = (joints,) + self.dims
        levels = len(self.dims)
        self.down = nn.ModuleList()
        for i in range(levels):
            cin, cout = widths[i], widths[i + 1]
            level = nn.Module()
            level.res0 = ResBlock(cin, cout, time_dim)
            level.res1 = ResBlock(cout, cout, time_dim)
            if i + 1 < levels:
                level.sample = nn.Conv1d(cout, cout, 3, stride=2, padding=1)
            self.down.append(level)
        mid = self.dims[-1]
        self.mid0 = ResBlock(mid, mid, time_dim)
        self.mid1 = ResBlock(mid, mid, time_dim)
        self.up = nn.ModuleList()
        for i in reversed(range(1, levels)):
            din, dout = widths[i], widths[i + 1]
            level = nn.Module()
            level.res0 = ResBlock(2 * dout, din, time_dim)
            level.res1 = ResBlock(din, din, time_dim)
            level.sample = nn.ConvTranspose1d(din, din, 4, stride=2, padding=1)
            self.up.append(level)
        self.final = ConvBlock((2 if top_skip else 1) * self.dims[0], self.dims[0])
        self.out = nn.Conv1d(self.dims[0], joints, 1)

    def lengths(self):
        """Sequence length at each level: 50, 25, 13, ..."""
        out = [HORIZON]
        for _ in range(len(self.dims) - 1):
            out.append((out[-1] - 1) // 2 + 1)
        return out

    def forward(self, x, t):
        temb = self.time_out(F.mish(self.time_in(time_features(t, self.time_dim))))
        skips = []
        for level in self.down:
            x = level.res0(x, temb)
            x = level.res1(x, temb)
            skips.append(x)
            if hasattr(level, "sample"):
                x = level.sample(x)
        x = self.mid0(x, temb)
        x = self.mid1(x, temb)
        lengths = self.lengths()
        for j, level in enumerate(self.up):
            x = torch.cat([x, skips.pop()], dim=1)
            x = level.res0(x, temb)
            x = level.res1(x, temb)
            x = level.sample(x)
            x = x[:, :, : lengths[len(self.dims) - 2 - j]]
        if self.top_skip:
            # Our fix: the original never consumes the first level's full-resolution skip, so
            # waypoint-scale detail (the white part of the noise) must survive a 2x downsampling.
            x = torch.cat([x, skips.pop()], dim=1)
        return self.out(self.final(x))

    def config(self):
        return {
            "dims": list(self.dims),
            "time_dim": self.time_dim,
            "time_hidden": self.time_hidden,
            "kernel": KERNEL,
            "groups": GROUPS,
            "horizon": HORIZON,
            "joints": self.joints,
            "lengths": self.lengths(),
            "top_skip": self.top_skip,
        }

    def macs(self):
        """Multiply-accumulates of one forward for one trajectory (convs and linears)."""
        total = 0
        hooks = []

        def conv_hook(m, inp, out):
            nonlocal total
            k = m.kernel_size[0]
            if isinstance(m, nn.ConvTranspose1d):
                total += inp[0].shape[-1] * m.in_channels * m.out_channels * k
            else:
                total += out.shape[-1] * m.in_channels * m.out_channels * k

        def linear_hook(m, inp, out):
            nonlocal total
            total += m.in_features * m.out_features

        for m in self.modules():
            if isinstance(m, (nn.Conv1d, nn.ConvTranspose1d)):
                hooks.append(m.register_forward_hook(conv_hook))
            elif isinstance(m, nn.Linear):
                hooks.append(m.register_forward_hook(linear_hook))
        with torch.no_grad():
            self(torch.zeros(1, self.joints, HORIZON), torch.ones(1))
        for h in hooks:
            h.remove()
        return total


def quantize(w: torch.Tensor):
    """Per-output-channel symmetric int8 (output channel = dim 0, or dim 1 of a ConvTranspose).

    scale = max|w| / 127 in float32, q = round-half-even(w / scale). `edmp-codegen` does the same
    float32 arithmetic, so both sides hold identical integers and scales.
    """
    w = w.detach().float()
    flat = w.reshape(w.shape[0], -1)
    maxabs = flat.abs().max(dim=1).values
    scale = torch.where(maxabs > 0, maxabs / 127.0, torch.ones_like(maxabs))
    q = torch.clamp(torch.round(flat / scale[:, None]), -127, 127)
    return q.reshape(w.shape), scale


def is_quantized(name: str, tensor: torch.Tensor) -> bool:
    """Weights of convolutions and linears are int8; biases and GroupNorm affines stay float32."""
    return name.endswith(".weight") and tensor.dim() >= 2


def fake_quantized(model: TemporalUNet) -> TemporalUNet:
    """A copy whose quantized weights are replaced by int8 * scale (float32)."""
    import copy

    fq = copy.deepcopy(model)
    with torch.no_grad():
        for name, p in fq.named_parameters():
            if not is_quantized(name, p):
                continue
            if ".sample." in name and isinstance(fq.get_submodule(name.rsplit(".", 1)[0]), nn.ConvTranspose1d):
                q, s = quantize(p.transpose(0, 1))
                p.copy_((q * s.reshape(-1, *([1] * (q.dim() - 1)))).transpose(0, 1))
            else:
                q, s = quantize(p)
                p.copy_(q * s.reshape(-1, *([1] * (q.dim() - 1))))
    return fq
