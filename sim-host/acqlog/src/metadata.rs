//! The `# key: value` lines at the top of a log.

use super::error::{AcqLogError, AcqLogErrorKind};
use std::fmt::Write as _;

/// Value of the `format:` line this crate writes and reads.
pub const FORMAT_NAME: &str = "sandjumper-acqlog";
/// Version of the format this crate writes; the reader accepts exactly this version.
pub const FORMAT_VERSION: u32 = 1;

/// Which one-cycle jump the log records, when it is one (docs/model.md section 2). Written as
/// `jump_kind`, `jump_amplitude_m`, `jump_freq_hz`, `jump_tau_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct JumpConfig {
    /// `single`, `stutter` or `delayed-stutter` (as the CLI spells it); free text is kept.
    pub kind: String,
    /// Stroke amplitude `A`, m.
    pub amplitude_m: Option<f64>,
    /// Forcing frequency `f`, Hz.
    pub freq_hz: Option<f64>,
    /// Delay `tau` of a delayed stutter, s.
    pub tau_s: Option<f64>,
}

/// Everything above the header line. Only `rate_hz` and `counts_per_m` are required.
///
/// Motor position relative to the rod (docs/model.md `p = x_m - x_r`) is recovered from a row as
/// `p_m = encoder_sign * encoder_counts / counts_per_m + position_offset_m`.
#[derive(Clone, Debug, PartialEq)]
pub struct LogMetadata {
    /// Sampling (control-tick) rate, Hz. Required.
    pub rate_hz: f64,
    /// Encoder counts per metre of motor travel relative to the rod. Required.
    pub counts_per_m: f64,
    /// `+1` (default, the convention of this project): counts increase when the motor moves
    /// up relative to the rod. `-1` for an encoder that counts the other way.
    pub encoder_sign: i8,
    /// Position `p` at encoder count zero, m (default 0).
    pub position_offset_m: f64,
    /// Firmware name and version that produced the samples, if known.
    pub firmware: Option<String>,
    /// What wrote the log (e.g. `sandjumper hil --link sil`), if known.
    pub source: Option<String>,
    /// The jump that was run, if the log records one.
    pub jump: Option<JumpConfig>,
    /// Packing fraction of the bed, if known.
    pub phi: Option<f64>,
    /// Samples the acquisition knows it lost (sequence-number gaps, queue overflow).
    pub dropped_samples: u64,
    /// Jump height measured on the rig (camera), m, if known: replay reports predicted vs
    /// measured.
    pub measured_jump_height_m: Option<f64>,
    /// Any other `key: value` lines, in file order, kept verbatim.
    pub extra: Vec<(String, String)>,
}

impl LogMetadata {
    /// Metadata with the two required values and every optional one at its default.
    pub fn new(rate_hz: f64, counts_per_m: f64) -> Self {
        Self {
            rate_hz,
            counts_per_m,
            encoder_sign: 1,
            position_offset_m: 0.0,
            firmware: None,
            source: None,
            jump: None,
            phi: None,
            dropped_samples: 0,
            measured_jump_height_m: None,
            extra: Vec::new(),
        }
    }

    /// Motor position relative to the rod for an encoder reading, m.
    pub fn position_m(&self, encoder_counts: i64) -> f64 {
        f64::from(self.encoder_sign) * encoder_counts as f64 / self.counts_per_m
            + self.position_offset_m
    }

    /// Sampling period `1 / rate_hz`, s.
    pub fn period_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// Checks the values a writer is about to write (the reader applies the same rules).
    pub fn validate(&self) -> Result<(), AcqLogError> {
        check_rate(self.rate_hz).map_err(bad_meta)?;
        check_counts_per_m(self.counts_per_m).map_err(bad_meta)?;
        if self.encoder_sign != 1 && self.encoder_sign != -1 {
            return Err(bad_meta(format!(
                "encoder_sign {} not allowed: +1 or -1",
                self.encoder_sign
            )));
        }
        for (key, value) in [
            ("position_offset_m", Some(self.position_offset_m)),
            ("phi", self.phi),
            ("measured_jump_height_m", self.measured_jump_height_m),
        ] {
            if let Some(v) = value
                && !v.is_finite()
            {
                return Err(bad_meta(format!("{key} = {v} is not a finite number")));
            }
        }
        for (key, value) in self.free_text() {
            if value.chars().any(|c| c.is_control() && c != '\t') {
                return Err(bad_meta(format!(
                    "{key} must fit on one line, without control characters"
                )));
            }
        }
        for (key, _) in &self.extra {
            check_key(key).map_err(bad_meta)?;
            if KNOWN_KEYS.contains(&key.as_str()) {
                return Err(bad_meta(format!(
                    "extra key `{key}` is a standard key: set the field instead"
                )));
            }
        }
        Ok(())
    }

    fn free_text(&self) -> Vec<(&str, &str)> {
        let mut out = Vec::new();
        if let Some(s) = &self.firmware {
            out.push(("firmware", s.as_str()));
        }
        if let Some(s) = &self.source {
            out.push(("source", s.as_str()));
        }
        if let Some(j) = &self.jump {
            out.push(("jump_kind", j.kind.as_str()));
        }
        for (k, v) in &self.extra {
            out.push((k.as_str(), v.as_str()));
        }
        out
    }

    /// The metadata block, one `# key: value` line each, `format` first.
    pub fn to_lines(&self) -> String {
        let mut s = String::new();
        let mut line = |key: &str, value: &dyn std::fmt::Display| {
            let _ = writeln!(s, "# {key}: {value}");
        };
        line("format", &format_args!("{FORMAT_NAME} {FORMAT_VERSION}"));
        line("rate_hz", &self.rate_hz);
        line("counts_per_m", &self.counts_per_m);
        line(
            "encoder_sign",
            &if self.encoder_sign < 0 { "-1" } else { "+1" },
        );
        line("position_offset_m", &self.position_offset_m);
        if let Some(v) = &self.firmware {
            line("firmware", v);
        }
        if let Some(v) = &self.source {
            line("source", v);
        }
        if let Some(j) = &self.jump {
            line("jump_kind", &j.kind);
            if let Some(v) = j.amplitude_m {
                line("jump_amplitude_m", &v);
            }
            if let Some(v) = j.freq_hz {
                line("jump_freq_hz", &v);
            }
            if let Some(v) = j.tau_s {
                line("jump_tau_s", &v);
            }
        }
        if let Some(v) = self.phi {
            line("phi", &v);
        }
        line("dropped_samples", &self.dropped_samples);
        if let Some(v) = self.measured_jump_height_m {
            line("measured_jump_height_m", &v);
        }
        for (k, v) in &self.extra {
            line(k, v);
        }
        s
    }
}

/// The keys with a meaning in this format (anything else goes to [`LogMetadata::extra`]).
pub const KNOWN_KEYS: &[&str] = &[
    "format",
    "rate_hz",
    "counts_per_m",
    "encoder_sign",
    "position_offset_m",
    "firmware",
    "source",
    "jump_kind",
    "jump_amplitude_m",
    "jump_freq_hz",
    "jump_tau_s",
    "phi",
    "dropped_samples",
    "measured_jump_height_m",
];

/// Highest sampling rate accepted, Hz.
pub const MAX_RATE_HZ: f64 = 1.0e6;

fn bad_meta(message: String) -> AcqLogError {
    AcqLogError::whole(AcqLogErrorKind::BadMetadataValue, message)
}

fn check_rate(rate_hz: f64) -> Result<(), String> {
    if rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= MAX_RATE_HZ {
        Ok(())
    } else {
        Err(format!(
            "rate_hz = {rate_hz} not allowed: a sampling rate > 0 and <= {MAX_RATE_HZ} Hz"
        ))
    }
}

fn check_counts_per_m(counts_per_m: f64) -> Result<(), String> {
    if counts_per_m.is_finite() && counts_per_m > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "counts_per_m = {counts_per_m} not allowed: a positive number of encoder counts per metre (1e6 for 1 um per count)"
        ))
    }
}

fn check_key(key: &str) -> Result<(), String> {
    let ok = !key.is_empty()
        && key
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "metadata key `{key}` not allowed: use lowercase letters, digits and `_`"
        ))
    }
}

/// Collects `# key: value` lines while the reader walks the top of a file.
#[derive(Default)]
pub(crate) struct MetadataBuilder {
    entries: Vec<(String, String, u64)>,
}

impl MetadataBuilder {
    /// Takes one line that starts with `#`. `##...` lines and a bare `#` are free comments.
    pub(crate) fn push_line(&mut self, line_no: u64, line: &str) -> Result<(), AcqLogError> {
        let body = &line[1..];
        if body.starts_with('#') || body.trim().is_empty() {
            return Ok(());
        }
        let malformed = |why: &str| {
            AcqLogError::at(
                line_no,
                AcqLogErrorKind::MalformedMetadata,
                format!(
                    "{why}: metadata lines are `# key: value` (free comments start with `##`); got `{}`",
                    truncate(line)
                ),
            )
        };
        if let Some(c) = body.chars().find(|c| c.is_control() && *c != '\t') {
            return Err(malformed(&format!(
                "control character U+{:04X} in a metadata line",
                u32::from(c)
            )));
        }
        let Some((key, value)) = body.split_once(':') else {
            if body.contains('=') {
                return Err(malformed("`=` used where `:` is expected"));
            }
            return Err(malformed("no `:` after the key"));
        };
        let key = key.trim();
        check_key(key).map_err(|why| malformed(&why))?;
        if let Some((_, _, first)) = self.entries.iter().find(|(k, _, _)| k == key) {
            return Err(AcqLogError::at(
                line_no,
                AcqLogErrorKind::MalformedMetadata,
                format!("metadata key `{key}` given twice (first on line {first})"),
            ));
        }
        self.entries
            .push((key.to_owned(), value.trim().to_owned(), line_no));
        Ok(())
    }

    /// Checks and converts the collected lines. `header_line` is used for "missing" errors.
    pub(crate) fn finish(self, header_line: u64) -> Result<LogMetadata, AcqLogError> {
        let find = |key: &str| self.entries.iter().find(|(k, _, _)| k == key);
        let bad =
            |line: u64, msg: String| AcqLogError::at(line, AcqLogErrorKind::BadMetadataValue, msg);
        let number = |key: &str| -> Result<Option<(f64, u64)>, AcqLogError> {
            match find(key) {
                None => Ok(None),
                Some((_, v, line)) => match v.parse::<f64>() {
                    Ok(x) if x.is_finite() => Ok(Some((x, *line))),
                    _ => Err(bad(*line, format!("{key} = `{v}` is not a finite number"))),
                },
            }
        };
        if let Some((_, v, line)) = find("format") {
            let expected = format!("{FORMAT_NAME} {FORMAT_VERSION}");
            if v.as_str() != expected {
                return Err(AcqLogError::at(
                    *line,
                    AcqLogErrorKind::UnsupportedFormat,
                    format!("format `{v}` not supported: this reader reads `{expected}`"),
                ));
            }
        }
        let required = |key: &str, what: &str| -> Result<(f64, u64), AcqLogError> {
            number(key)?.ok_or_else(|| {
                let hint = self
                    .entries
                    .iter()
                    .find(|(k, _, _)| k.starts_with(&key[..4]))
                    .map(|(k, _, l)| format!(" (line {l} has `{k}`; the key is `{key}`)"))
                    .unwrap_or_default();
                AcqLogError::at(
                    header_line,
                    AcqLogErrorKind::MissingMetadata,
                    format!("metadata `# {key}: ...` missing before the header ({what}){hint}"),
                )
            })
        };
        let (rate_hz, rate_line) = required("rate_hz", "the sampling rate, Hz")?;
        check_rate(rate_hz).map_err(|m| bad(rate_line, m))?;
        let (counts_per_m, cpm_line) = required(
            "counts_per_m",
            "encoder counts per metre, e.g. 1e6 for 1 um per count",
        )?;
        check_counts_per_m(counts_per_m).map_err(|m| bad(cpm_line, m))?;
        let mut meta = LogMetadata::new(rate_hz, counts_per_m);
        if let Some((_, v, line)) = find("encoder_sign") {
            meta.encoder_sign = match v.as_str() {
                "+1" | "1" => 1,
                "-1" => -1,
                _ => {
                    return Err(bad(
                        *line,
                        format!(
                            "encoder_sign `{v}` not allowed: +1 (counts increase when the motor moves up relative to the rod) or -1"
                        ),
                    ));
                }
            }
        }
        if let Some((x, _)) = number("position_offset_m")? {
            meta.position_offset_m = x;
        }
        meta.firmware = find("firmware").map(|(_, v, _)| v.clone());
        meta.source = find("source").map(|(_, v, _)| v.clone());
        if let Some((x, line)) = number("phi")? {
            if !(0.0..1.0).contains(&x) {
                return Err(bad(
                    line,
                    format!("phi = {x} not allowed: a packing fraction in [0, 1)"),
                ));
            }
            meta.phi = Some(x);
        }
        if let Some((_, v, line)) = find("dropped_samples") {
            meta.dropped_samples = v.parse::<u64>().map_err(|_| {
                bad(
                    *line,
                    format!("dropped_samples `{v}` not allowed: a whole number >= 0"),
                )
            })?;
        }
        if let Some((x, line)) = number("measured_jump_height_m")? {
            if x < 0.0 {
                return Err(bad(
                    line,
                    format!("measured_jump_height_m = {x} must be >= 0"),
                ));
            }
            meta.measured_jump_height_m = Some(x);
        }
        let amplitude_m = number("jump_amplitude_m")?.map(|(x, _)| x);
        let freq_hz = number("jump_freq_hz")?.map(|(x, _)| x);
        let tau_s = number("jump_tau_s")?.map(|(x, _)| x);
        match find("jump_kind") {
            Some((_, kind, _)) => {
                meta.jump = Some(JumpConfig {
                    kind: kind.clone(),
                    amplitude_m,
                    freq_hz,
                    tau_s,
                })
            }
            None => {
                if let Some((k, _, line)) =
                    self.entries.iter().find(|(k, _, _)| k.starts_with("jump_"))
                {
                    return Err(bad(*line, format!("`{k}` given without `jump_kind`")));
                }
            }
        }
        meta.extra = self
            .entries
            .iter()
            .filter(|(k, _, _)| !KNOWN_KEYS.contains(&k.as_str()))
            .map(|(k, v, _)| (k.clone(), v.clone()))
            .collect();
        Ok(meta)
    }
}

/// At most 80 characters of a line, for error messages.
pub(crate) fn truncate(line: &str) -> String {
    if line.chars().count() <= 80 {
        line.to_owned()
    } else {
        let mut s: String = line.chars().take(77).collect();
        s.push_str("...");
        s
    }
}
