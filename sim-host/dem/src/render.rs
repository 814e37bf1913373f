//! Pictures of a DEM world: side-wall camera frames (grey disks with random intensities, so
//! that `sandjumper piv` runs on DEM output as on the lab's 500 fps video), and snapshots
//! with the grains coloured by speed (the animation's frames).

use serde::Serialize;

use super::grains::FREE;
use super::world::World;

/// The virtual side-wall camera: what part of the world, at what scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SideCamera {
    /// Metres per pixel.
    pub m_per_px: f64,
    /// World x of the image's left edge, m.
    pub left_m: f64,
    /// World height of the image's top edge, m.
    pub top_m: f64,
    /// Width, px.
    pub width_px: u32,
    /// Height, px.
    pub height_px: u32,
}

impl SideCamera {
    /// Image position of a world point, px: pixel (row i, column j) is centred at x = j,
    /// y = i (as numpy, scikit-image, OpenCV and this project's PIV have it), so the frame's
    /// left edge `left_m` is at x = -0.5 and its top `top_m` at y = -0.5.
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (x - self.left_m) / self.m_per_px - 0.5,
            (self.top_m - y) / self.m_per_px - 0.5,
        )
    }
}

/// A grain's grey level from its identity and the seed: 90..230, fixed for the grain.
pub fn grain_intensity(id: u32, seed: u64) -> f64 {
    let mut h = (u64::from(id) ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15))
        .wrapping_add(0x632b_e59b_d9b4_e019);
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    90.0 + 140.0 * (h >> 11) as f64 / (1u64 << 53) as f64
}

/// A disc to draw in the camera's plane: a grain, or a piece of the intruder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    /// Its centre's horizontal position, m.
    pub x_m: f64,
    /// Its centre's height, m.
    pub h_m: f64,
    /// Its radius, m.
    pub radius_m: f64,
    /// The grain's identity (its grey level, [`grain_intensity`]).
    pub id: u32,
    /// Drawn black: the intruder.
    pub intruder: bool,
}

/// Paint disks: `paint(px_index, coverage, disc, distance_over_radius)` for every pixel a
/// disk covers, with anti-aliased coverage of its edge, in the order given (later on top).
fn for_each_disk_pixel(
    discs: impl Iterator<Item = Disc>,
    cam: &SideCamera,
    mut paint: impl FnMut(usize, f64, (usize, &Disc), f64),
) {
    let (wpx, hpx) = (cam.width_px as i64, cam.height_px as i64);
    for (i, disc) in discs.enumerate() {
        let (cx, cy) = cam.to_px(disc.x_m, disc.h_m);
        let r = disc.radius_m / cam.m_per_px;
        let (x0, x1) = ((cx - r - 1.0).floor() as i64, (cx + r + 1.0).ceil() as i64);
        let (y0, y1) = ((cy - r - 1.0).floor() as i64, (cy + r + 1.0).ceil() as i64);
        if x1 < 0 || y1 < 0 || x0 >= wpx || y0 >= hpx {
            continue;
        }
        for py in y0.max(0)..y1.min(hpx) {
            for px in x0.max(0)..x1.min(wpx) {
                let dx = px as f64 - cx;
                let dy = py as f64 - cy;
                let d = (dx * dx + dy * dy).sqrt();
                let cover = (r - d + 0.5).clamp(0.0, 1.0);
                if cover > 0.0 {
                    paint(
                        (py * wpx + px) as usize,
                        cover,
                        (i, &disc),
                        (d / r).min(1.0),
                    );
                }
            }
        }
    }
}

/// The world's grains as discs, in their order.
fn discs(w: &World) -> impl Iterator<Item = Disc> + '_ {
    let g = &w.g;
    (0..g.len()).map(|i| Disc {
        x_m: g.x[i],
        h_m: g.y[i],
        radius_m: g.radius[i],
        id: g.id[i],
        intruder: g.kind[i] != FREE,
    })
}

/// A side-wall frame: dark background, each free grain a disk of its own grey level shaded
/// toward its edge, the intruder black. 8-bit grey.
pub fn side_wall_frame(w: &World, cam: &SideCamera, seed: u64) -> image::GrayImage {
    disc_frame(discs(w), cam, seed)
}

/// [`side_wall_frame`] of any discs (a 3-D bed's grains seen through its wall, say), drawn in
/// the order given, later ones on top.
pub fn disc_frame(
    discs: impl Iterator<Item = Disc>,
    cam: &SideCamera,
    seed: u64,
) -> image::GrayImage {
    let n = (cam.width_px * cam.height_px) as usize;
    let mut buf = vec![25.0f64; n];
    for_each_disk_pixel(discs, cam, |k, cover, (_, disc), rr| {
        let level = if disc.intruder {
            5.0
        } else {
            grain_intensity(disc.id, seed) * (1.0 - 0.45 * rr * rr)
        };
        buf[k] = buf[k] * (1.0 - cover) + level * cover;
    });
    image::GrayImage::from_fn(cam.width_px, cam.height_px, |x, y| {
        image::Luma([buf[(y * cam.width_px + x) as usize]
            .round()
            .clamp(0.0, 255.0) as u8])
    })
}

/// A snapshot: free grains coloured by speed (0 to `v_max_m_s`, viridis), the intruder red.
pub fn speed_snapshot(w: &World, cam: &SideCamera, v_max_m_s: f64) -> image::RgbaImage {
    let n = (cam.width_px * cam.height_px) as usize;
    let mut buf = vec![[250.0f64, 250.0, 250.0]; n];
    for_each_disk_pixel(discs(w), cam, |k, cover, (i, _), _| {
        let c = if w.g.kind[i] == FREE {
            let s = w.u.x[i].hypot(w.u.y[i]) / v_max_m_s.max(1e-12);
            let c = sandjumper_flow::figure::colour(s);
            [f64::from(c.0), f64::from(c.1), f64::from(c.2)]
        } else {
            [200.0, 30.0, 30.0]
        };
        for ch in 0..3 {
            buf[k][ch] = buf[k][ch] * (1.0 - cover) + c[ch] * cover;
        }
    });
    image::RgbaImage::from_fn(cam.width_px, cam.height_px, |x, y| {
        let c = buf[(y * cam.width_px + x) as usize];
        image::Rgba([c[0] as u8, c[1] as u8, c[2] as u8, 255])
    })
}
