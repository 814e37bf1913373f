//! The firmware's defmt log: the RTT up-buffer 0 drained from target memory at every stop (as a
//! probe does), decoded with the ELF's `.defmt` table.

use defmt_decoder::{DecodeError, Table};
use rigless::emulator::Host;
use rigless::soc::Width;

/// Drains `_SEGGER_RTT`'s up-buffer 0 and decodes what it holds.
pub struct RttLog {
    control_block: u64,
    table: Option<Table>,
    bytes: Vec<u8>,
    decoded_up_to: usize,
    /// Decoded log lines so far.
    pub lines: Vec<String>,
    /// Frames the decoder could not decode.
    pub malformed: u64,
}

impl std::fmt::Debug for RttLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RttLog")
            .field("bytes", &self.bytes.len())
            .field("lines", &self.lines.len())
            .finish()
    }
}

fn read32(host: &mut dyn Host, address: u64) -> u64 {
    host.read(address, Width::W32).unwrap_or(0)
}

impl RttLog {
    /// The log of the ELF `elf` (its bytes): finds `_SEGGER_RTT` and the defmt table.
    pub fn new(elf: &[u8]) -> Result<Self, String> {
        let symbols = rigless::symbols::Symbols::read(elf, |a| a & !1)
            .map_err(|e| format!("cannot read the ELF's symbols: {e}"))?;
        let control_block = symbols
            .get("_SEGGER_RTT")
            .map_err(|e| format!("the ELF has no _SEGGER_RTT (defmt-rtt): {e}"))?;
        let table =
            Table::parse(elf).map_err(|e| format!("cannot read the ELF's defmt table: {e}"))?;
        Ok(Self {
            control_block,
            table,
            bytes: Vec::new(),
            decoded_up_to: 0,
            lines: Vec::new(),
            malformed: 0,
        })
    }

    /// Moves what the firmware wrote since the last call out of its buffer; returns the new
    /// decoded lines.
    pub fn drain(&mut self, host: &mut dyn Host) -> &[String] {
        // SEGGER RTT control block: 16-byte id, 2 counts, then up-buffer 0:
        // name, buffer, size, write offset, read offset, flags (6 words).
        let up = self.control_block + 24;
        let (buf, size, wr, rd) = (
            read32(host, up + 4),
            read32(host, up + 8),
            read32(host, up + 12),
            read32(host, up + 16),
        );
        let first = self.lines.len();
        if size == 0 || buf == 0 || wr >= size || rd >= size {
            return &self.lines[first..];
        }
        let mut r = rd;
        while r != wr {
            self.bytes
                .push(host.read(buf + r, Width::W8).unwrap_or(0) as u8);
            r = (r + 1) % size;
        }
        let _ = host.write(up + 16, Width::W32, r);
        self.decode();
        &self.lines[first..]
    }

    fn decode(&mut self) {
        let Some(table) = &self.table else { return };
        let mut decoder = table.new_stream_decoder();
        decoder.received(&self.bytes[self.decoded_up_to..]);
        // Frames are decoded from the start of what is undecoded; a partial frame waits.
        let mut lines = Vec::new();
        loop {
            match decoder.decode() {
                Ok(frame) => lines.push(frame.display_message().to_string()),
                Err(DecodeError::UnexpectedEof) => break,
                Err(DecodeError::Malformed) => {
                    self.malformed += 1;
                    if !table.encoding().can_recover() {
                        break;
                    }
                }
            }
        }
        if !lines.is_empty() {
            // rzCOBS frames end with a zero byte: what was decoded is up to the last zero.
            if let Some(last_zero) = self.bytes.iter().rposition(|&b| b == 0) {
                self.decoded_up_to = last_zero + 1;
            }
            self.lines.extend(lines);
        }
    }

    /// Puts up-buffer 0 in blocking mode (`SEGGER_RTT_MODE_BLOCK_IF_FULL`), as probe-rs does
    /// when it attaches.
    pub fn set_blocking(&self, host: &mut dyn Host) {
        let flags = self.control_block + 24 + 20;
        let _ = host.write(flags, Width::W32, 2);
    }

    /// A probe attached from power-up that stopped reading and left up-buffer 0 full: blocking
    /// mode, and the read offset one past the write offset (no byte free). False while the
    /// firmware has not set the buffer up yet (its address or size still zero).
    pub fn block_full(&self, host: &mut dyn Host) -> bool {
        let up = self.control_block + 24;
        let (buf, size, wr) = (
            read32(host, up + 4),
            read32(host, up + 8),
            read32(host, up + 12),
        );
        if size == 0 || buf == 0 || wr >= size {
            return false;
        }
        self.set_blocking(host);
        let _ = host.write(up + 16, Width::W32, (wr + 1) % size);
        true
    }

    /// Every byte read from the buffer.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}
