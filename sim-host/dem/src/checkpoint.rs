//! Checkpoints: a world's whole state in one file, so a bed is prepared once and intrusions
//! start from it, and a stopped intrusion resumes to the same bits.
//!
//! Layout (little-endian): the magic `SJDEMCK1`, a format version (u32), a JSON header
//! (length-prefixed: the run's parameters, time, step, and the caller's own record), the
//! per-grain arrays in slot order, the contacts' tangential histories by grain identity, an
//! extra f64 array for the caller, and an FNV-1a 64 checksum of everything before it. A file
//! that is cut, edited or of another version is refused with what is wrong; it is written to
//! a temporary name and renamed, so a crash never leaves half a checkpoint under the name.

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::grains::Grains;
use super::world::{Velocities, World, WorldConfig};

const MAGIC: &[u8; 8] = b"SJDEMCK1";
/// Format version.
pub const VERSION: u32 = 1;

/// The header.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Header {
    cfg: WorldConfig,
    t_s: f64,
    steps: u64,
    intruder_next: Option<(f64, f64)>,
    grains: u64,
    record: serde_json::Value,
}

fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Serialise `w` with the caller's `record` (JSON) and `extra` array.
pub fn encode(w: &World, record: &serde_json::Value, extra: &[f64]) -> Vec<u8> {
    let g = &w.g;
    let n = g.len();
    let header = Header {
        cfg: w.cfg,
        t_s: w.t_s,
        steps: w.steps,
        intruder_next: w.intruder_next,
        grains: n as u64,
        record: record.clone(),
    };
    let hj = serde_json::to_vec(&header).unwrap_or_default();
    let mut b = Vec::with_capacity(64 + hj.len() + n * 120 + extra.len() * 8);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&VERSION.to_le_bytes());
    b.extend_from_slice(&(hj.len() as u64).to_le_bytes());
    b.extend_from_slice(&hj);
    for &id in &g.id {
        b.extend_from_slice(&id.to_le_bytes());
    }
    b.extend_from_slice(&g.kind);
    for arr in [
        &g.x,
        &g.y,
        &g.vx,
        &g.vy,
        &g.w,
        &w.u.x,
        &w.u.y,
        &w.u.w,
        &g.radius,
        &g.inv_mass,
        &g.inv_inertia,
    ] {
        for &v in arr.iter() {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    for h in &w.wall_hist {
        for v in h {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    let hist = w.nl.history_by_id(g);
    b.extend_from_slice(&(hist.len() as u64).to_le_bytes());
    for (a, c, h) in hist {
        b.extend_from_slice(&a.to_le_bytes());
        b.extend_from_slice(&c.to_le_bytes());
        b.extend_from_slice(&h.to_le_bytes());
    }
    b.extend_from_slice(&(extra.len() as u64).to_le_bytes());
    for v in extra {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let sum = fnv1a(&b);
    b.extend_from_slice(&sum.to_le_bytes());
    b
}

/// Write a checkpoint atomically.
pub fn save(
    path: &Path,
    w: &World,
    record: &serde_json::Value,
    extra: &[f64],
) -> Result<(), String> {
    let bytes = encode(w, record, extra);
    let tmp = path.with_extension("ckpt.tmp");
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| format!("cannot write checkpoint {}: {e}", path.display()))
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| {
                format!(
                    "cut short: needs {n} more bytes at offset {} of {}",
                    self.at,
                    self.b.len()
                )
            })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or([0; 8]),
        ))
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().unwrap_or([0; 4]),
        ))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or([0; 8]),
        ))
    }
    fn f64s(&mut self, n: usize) -> Result<Vec<f64>, String> {
        let raw = self.take(n.checked_mul(8).ok_or("length overflows")?)?;
        Ok(raw
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect())
    }
}

/// A checkpoint read back: the world, the caller's record and extra array.
#[derive(Debug)]
pub struct Loaded {
    /// The world, its neighbour list rebuilt and histories restored.
    pub world: World,
    /// The caller's record.
    pub record: serde_json::Value,
    /// The caller's extra array.
    pub extra: Vec<f64>,
}

/// Decode a checkpoint; errors say what is wrong.
pub fn decode(b: &[u8]) -> Result<Loaded, String> {
    if b.len() < 8 + 4 + 8 || &b[..8] != MAGIC {
        return Err("not a sandjumper DEM checkpoint (no SJDEMCK1 magic)".into());
    }
    let (body, tail) = b.split_at(b.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().unwrap_or([0; 8]));
    let mut r = Reader { b: body, at: 8 };
    let version = r.u32()?;
    if version != VERSION {
        return Err(format!(
            "format version {version} (this build reads version {VERSION})"
        ));
    }
    if fnv1a(body) != stored {
        return Err("corrupt: the checksum does not match the contents".into());
    }
    let hl = r.u64()? as usize;
    let header: Header =
        serde_json::from_slice(r.take(hl)?).map_err(|e| format!("corrupt header: {e}"))?;
    let n = usize::try_from(header.grains).map_err(|_| "grain count overflows")?;
    let id = r
        .take(n.checked_mul(4).ok_or("length overflows")?)?
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().unwrap_or([0; 4])))
        .collect();
    let kind = r.take(n)?.to_vec();
    let (x, y, vx, vy, w) = (r.f64s(n)?, r.f64s(n)?, r.f64s(n)?, r.f64s(n)?, r.f64s(n)?);
    let u = Velocities {
        x: r.f64s(n)?,
        y: r.f64s(n)?,
        w: r.f64s(n)?,
    };
    let g = Grains {
        id,
        x,
        y,
        vx,
        vy,
        w,
        radius: r.f64s(n)?,
        inv_mass: r.f64s(n)?,
        inv_inertia: r.f64s(n)?,
        kind,
    };
    let wh = r.f64s(n.checked_mul(4).ok_or("length overflows")?)?;
    let nh = r.u64()? as usize;
    let mut hist = Vec::with_capacity(nh.min(body.len() / 16));
    for _ in 0..nh {
        hist.push((r.u32()?, r.u32()?, r.f64()?));
    }
    let ne = r.u64()? as usize;
    let extra = r.f64s(ne)?;
    if r.at != body.len() {
        return Err(format!("{} unexpected bytes at the end", body.len() - r.at));
    }
    if g.x.iter().chain(&g.y).any(|v| !v.is_finite()) {
        return Err("corrupt: a grain position is not finite".into());
    }
    let mut world = World::new(header.cfg, Grains::default());
    world.g = g;
    world.u = u;
    world.wall_hist = wh
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    world.t_s = header.t_s;
    world.steps = header.steps;
    world.intruder_next = header.intruder_next;
    world.rebuild();
    world.nl.restore_history(&world.g, &hist);
    Ok(Loaded {
        world,
        record: header.record,
        extra,
    })
}

/// Read a checkpoint file; errors name the file.
pub fn load(path: &Path) -> Result<Loaded, String> {
    let b = std::fs::read(path)
        .map_err(|e| format!("cannot read checkpoint {}: {e}", path.display()))?;
    decode(&b).map_err(|e| format!("checkpoint {}: {e}", path.display()))
}
