//! The columns of a log and one row of samples.

/// A column the format defines. Extra columns are allowed only with an `x_` prefix (kept out
/// of the data, never an error), so a misspelt standard column is caught.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// Control tick number (u64). Written by sandjumper; optional for third-party logs.
    Tick,
    /// Sample time, s. Required.
    TimeS,
    /// Encoder count (i64). Required.
    EncoderCounts,
    /// Commanded motor position relative to the rod, m.
    PCmdM,
    /// Force command sent to the drive, N.
    ForceCmdN,
    /// Measured motor current, A.
    CurrentA,
    /// Camera frame number triggered at this tick (empty when none).
    CameraFrame,
    /// Controller status flags (`sandjumper_core` sample flags), decimal or `0x` hex.
    Flags,
    /// Measured rod height above its rest height, m (camera; empty when not measured).
    RodHeightM,
}

impl Column {
    /// Every column, in the order the writer writes them.
    pub const ALL: [Column; 9] = [
        Column::Tick,
        Column::TimeS,
        Column::EncoderCounts,
        Column::PCmdM,
        Column::ForceCmdN,
        Column::CurrentA,
        Column::CameraFrame,
        Column::Flags,
        Column::RodHeightM,
    ];

    /// Header name.
    pub fn name(self) -> &'static str {
        match self {
            Column::Tick => "tick",
            Column::TimeS => "t_s",
            Column::EncoderCounts => "encoder_counts",
            Column::PCmdM => "p_cmd_m",
            Column::ForceCmdN => "force_cmd_n",
            Column::CurrentA => "current_a",
            Column::CameraFrame => "camera_frame",
            Column::Flags => "flags",
            Column::RodHeightM => "rod_height_m",
        }
    }

    /// The column with this header name.
    pub fn from_name(name: &str) -> Option<Column> {
        Column::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Whether every row must have a value.
    pub fn required(self) -> bool {
        matches!(self, Column::TimeS | Column::EncoderCounts)
    }
}

/// Which optional columns a log carries (`t_s` and `encoder_counts` always).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ColumnSet {
    bits: u16,
}

impl ColumnSet {
    /// The two required columns only.
    pub fn required() -> Self {
        Self::default()
            .with(Column::TimeS)
            .with(Column::EncoderCounts)
    }

    /// The columns sandjumper's own logs always have: `tick,t_s,encoder_counts`.
    pub fn sandjumper() -> Self {
        Self::required().with(Column::Tick)
    }

    /// This set plus one column.
    pub fn with(self, column: Column) -> Self {
        Self {
            bits: self.bits | (1 << column as u16),
        }
    }

    /// Whether the set has this column.
    pub fn contains(self, column: Column) -> bool {
        self.bits & (1 << column as u16) != 0
    }

    /// The columns in writing order.
    pub fn iter(self) -> impl Iterator<Item = Column> {
        Column::ALL.into_iter().filter(move |c| self.contains(*c))
    }
}

/// One control tick. Optional fields are `None` when the column is absent or the cell empty.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LogRow {
    /// Control tick number (`None` in a third-party log without a `tick` column).
    pub tick: Option<u64>,
    /// Sample time, s.
    pub t_s: f64,
    /// Encoder count; see [`super::LogMetadata::position_m`].
    pub encoder_counts: i64,
    /// Commanded position, m.
    pub p_cmd_m: Option<f64>,
    /// Force command, N.
    pub force_cmd_n: Option<f64>,
    /// Measured current, A.
    pub current_a: Option<f64>,
    /// Camera frame triggered at this tick.
    pub camera_frame: Option<u64>,
    /// Status flags.
    pub flags: Option<u32>,
    /// Measured rod height above rest, m.
    pub rod_height_m: Option<f64>,
}

impl LogRow {
    /// A row with the required values and a tick; every optional value `None`.
    pub fn new(tick: u64, t_s: f64, encoder_counts: i64) -> Self {
        Self {
            tick: Some(tick),
            t_s,
            encoder_counts,
            ..Self::default()
        }
    }

    /// Whether the row has a value for this column.
    pub fn has(&self, column: Column) -> bool {
        match column {
            Column::Tick => self.tick.is_some(),
            Column::TimeS | Column::EncoderCounts => true,
            Column::PCmdM => self.p_cmd_m.is_some(),
            Column::ForceCmdN => self.force_cmd_n.is_some(),
            Column::CurrentA => self.current_a.is_some(),
            Column::CameraFrame => self.camera_frame.is_some(),
            Column::Flags => self.flags.is_some(),
            Column::RodHeightM => self.rod_height_m.is_some(),
        }
    }
}
