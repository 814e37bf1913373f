//! Ground modes and their guards (MODEL.md section 3).

use serde::Serialize;

/// Where the foot is with respect to the ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum GroundMode {
    /// In the air: `F_GM = 0`.
    Aerial,
    /// At rest, held by the sand (or the floor): `F_GM = L`.
    Static,
    /// Moving into the sand: `F_GM` follows the force law.
    Intruding,
}

impl GroundMode {
    /// Name as written in outputs.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Aerial => "Aerial",
            Self::Static => "Static",
            Self::Intruding => "Intruding",
        }
    }
}

impl core::fmt::Display for GroundMode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}
