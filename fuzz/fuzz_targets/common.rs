//! Helpers shared by the `wire`, `ik`, `search` and `checker` targets (included with `#[path]`).
#![allow(dead_code)]

use edmp_core::scene::{Obstacle, Scene};

/// Reads fuzz bytes as numbers; past the end it reads zeros.
pub struct Reader<'a>(pub &'a [u8]);

impl Reader<'_> {
    pub fn byte(&mut self) -> u8 {
        let (&b, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        b
    }
    pub fn raw(&mut self) -> f32 {
        f32::from_le_bytes([self.byte(), self.byte(), self.byte(), self.byte()])
    }
    /// Raw bits half the time (NaN, infinities, huge values), a tame value in [-4, 4) otherwise.
    pub fn f32(&mut self) -> f32 {
        let raw = self.raw();
        if self.byte() & 1 == 0 { raw } else { (raw.to_bits() % 8000) as f32 / 1000.0 - 4.0 }
    }
    pub fn array<const M: usize>(&mut self) -> [f32; M] {
        core::array::from_fn(|_| self.f32())
    }
}

/// Up to `N` fuzzed obstacles (quaternions normalised when possible, so valid shapes are common).
pub fn scene<const N: usize>(r: &mut Reader) -> Scene<'static, N> {
    let mut scene = Scene::<N>::new();
    let count = usize::from(r.byte()) % (N + 1);
    for _ in 0..count {
        let (kind, center, size, quat) = (r.byte(), r.array::<3>(), r.array::<3>(), r.array::<4>());
        let n = quat.iter().map(|v| v * v).sum::<f32>().sqrt();
        let q = if n.is_finite() && n > 1e-3 { quat.map(|v| v / n) } else { [1.0, 0.0, 0.0, 0.0] };
        let built = match kind % 3 {
            0 => Obstacle::cuboid(center, size, q),
            1 => Obstacle::cylinder(center, size[0], size[1], q),
            _ => Obstacle::sphere(center, size[0]),
        };
        if let Ok(o) = built {
            scene.push(o).expect("at most N obstacles");
        }
    }
    if r.byte() & 3 == 0 {
        let (center, radius) = (r.array::<3>(), r.f32());
        if let Ok(o) = Obstacle::sphere(center, radius) {
            scene.hold(o);
        }
    }
    scene
}

pub fn finite(q: &[f32]) -> bool {
    q.iter().all(|x| x.is_finite())
}
