//! The rig firmware on the STM32F407: RTIC 2.
//!
//! Priorities (higher preempts lower):
//! - 3 `control_tick` (TIM7 at [`board::TICK_HZ`]): the tick's start time to the core (a gap
//!   of more than 1.5 periods is a missed tick), the encoder and the current sample read
//!   first, then the core tick -> DAC + drive enable -> camera trigger, then at most one host
//!   command from the inbound queue (after the outputs, so its cost never shifts them), cycle-counted with the DWT (the count goes into the next
//!   tick's `TickTiming`, so the core latches `DeadlineOverrun` past
//!   [`board::TICK_BUDGET_CYCLES`]); sample records move to the telemetry queue; the watchdog
//!   is fed. It owns the core's `Rig` and the peripherals outright. It never logs: a full RTT
//!   buffer in blocking mode (a probe attached, or one that went away) would stall it with the
//!   drive on. What it would have said is counted in the core's `Status`.
//! - 1 `host_link` (OTG_FS interrupt, also pended by the tick): USB CDC, frame decoding,
//!   replies, telemetry batches. It talks to the tick only through lock-free single-producer
//!   single-consumer queues, so nothing it does can block the tick. The USB driver's own
//!   critical sections mask every interrupt (the HAL's single-core implementation), which
//!   delays the tick's entry by up to ~6 us at 168 MHz (the board's `bring_up.rs` bounds it).
//!
//! Losses are counted: sample records that find the telemetry queue full stay in the core's
//! queue, whose overflow the core counts (`samples_dropped` in every `Status`, and as gaps in
//! the sequence numbers); frames the link cannot queue, either way, are counted in the core's
//! `frames_dropped` (the link task's count reaches the tick through an atomic counter). Only
//! `init` and the fault handlers log: a defmt write holds a critical section (every interrupt
//! masked), and RTT is non-blocking (`disable-blocking-mode`), so a probe that stops reading
//! loses log lines instead of stalling the tick.
//!
//! Hardware-in-the-loop on the real board: the first `HostMessage::Sensor` frame switches the
//! tick to lockstep (one core tick per sensor frame, the actuator frame sent back) until reset;
//! the real drive stays disabled at zero force and the real bed apparatus off in that mode, and
//! the real emergency stop still stops (its loop reaches the core every tick in every mode). The core restarts its encoder
//! extension on entry (the host's count replaces TIM2's) and latches `LinkLost` when sensor
//! frames stop for [`LOCKSTEP_TIMEOUT_TICKS`] timer ticks.
//!
//! At start-up the reset cause (RCC_CSR) goes to the core: after anything but a power-on
//! reset, `Arm` is refused until the host sends `AcknowledgeReset`.

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use crate::board::f407::{self as board, RigIo};
    use crate::drive;
    use crate::link;
    use core::sync::atomic::{AtomicU32, Ordering};
    use cortex_m::peripheral::DWT;
    use heapless::spsc::{Consumer, Producer, Queue};
    use sandjumper_core::bed::BedOutputs;
    use sandjumper_core::protocol::{FrameDecoder, MAX_FRAME, SAMPLE_BATCH, encode_frame};
    use sandjumper_core::{
        CounterWidth, HostMessage, Rig, RigConfig, RigMessage, SampleRecord, TickInput, TickTiming,
    };
    use stm32f4xx_hal::otg_fs::{UsbBus, UsbBusType};
    use stm32f4xx_hal::pac::Interrupt;
    use usb_device::prelude::*;
    use usbd_serial::SerialPort;

    /// The core's own sample queue: drained into [`SAMPLES`] every tick, so it only buffers
    /// while the telemetry queue is full.
    const CORE_QUEUE: usize = 64;
    /// Telemetry queue between the tick and the link, records (capacity N - 1): ~50 ms at
    /// 10 kHz.
    const SAMPLES: usize = 512;
    /// Host frames waiting for the tick (capacity N - 1).
    const INBOUND: usize = 8;
    /// Messages waiting for the link (capacity N - 1).
    const OUTBOUND: usize = 8;
    /// Timer ticks in lockstep without a sensor frame before `LinkLost`: 50 ms (USB full speed
    /// delivers a frame per 1 ms USB frame at best, so tens of ticks pass between frames).
    pub const LOCKSTEP_TIMEOUT_TICKS: u32 = board::TICK_HZ / 20;
    /// Frames the link task lost (host frames it could not queue for the tick, messages that did
    /// not fit a frame), not yet handed to the core's `frames_dropped`. The link task never logs:
    /// defmt's RTT write masks every interrupt, the tick's included, and blocks while a probe's
    /// buffer is full.
    static INBOUND_DROPPED: AtomicU32 = AtomicU32::new(0);

    type Serial = SerialPort<'static, UsbBusType, [u8; 256], [u8; 1024]>;

    /// A frame from the host, in arrival order (a burst of rejects latches `LinkCorrupted`).
    // Fixed-size slots in a static queue: no heap to box into, and the size is what it is.
    #[allow(clippy::large_enum_variant)]
    pub enum Inbound {
        Message(HostMessage),
        Rejected,
    }

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        io: RigIo,
        rig: Rig<CORE_QUEUE>,
        inbound_rx: Consumer<'static, Inbound>,
        outbound_tx: Producer<'static, RigMessage>,
        samples_tx: Producer<'static, SampleRecord>,
        inbound_tx: Producer<'static, Inbound>,
        outbound_rx: Consumer<'static, RigMessage>,
        samples_rx: Consumer<'static, SampleRecord>,
        usb_dev: UsbDevice<'static, UsbBusType>,
        serial: Serial,
        decoder: FrameDecoder,
    }

    #[init(local = [
        serial_number: [u8; 24] = [0; 24],
        ep_memory: [u32; 1024] = [0; 1024],
        usb_bus: Option<usb_device::bus::UsbBusAllocator<UsbBusType>> = None,
        inbound: Queue<Inbound, INBOUND> = Queue::new(),
        outbound: Queue<RigMessage, OUTBOUND> = Queue::new(),
        samples: Queue<SampleRecord, SAMPLES> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut core = cx.core;
        core.DCB.enable_trace();
        core.DWT.enable_cycle_counter();
        let reset_cause = board::take_reset_cause();
        let parts = board::init(cx.device);
        let mut io = parts.io;

        let config = RigConfig {
            tick_hz: board::TICK_HZ,
            counter_width: CounterWidth::Bits32,
            deadline_cycles: board::TICK_BUDGET_CYCLES,
            tick_period_cycles: board::TICK_PERIOD_CYCLES,
            lockstep_timeout_ticks: LOCKSTEP_TIMEOUT_TICKS,
            // PE14, read every tick: `Arm` waits for the loop to read closed.
            emergency_stop_input: true,
            ..RigConfig::default()
        };
        let mut rig = match Rig::new(config) {
            Ok(rig) => rig,
            // The board's fixed configuration is checked by the core; a bad one is a build
            // defect: stay safe and say so.
            Err(e) => {
                board::force_safe_state();
                defmt::panic!("rig configuration rejected: {}", e)
            }
        };

        rig.set_reset_cause(reset_cause);

        let usb_bus = cx
            .local
            .usb_bus
            .insert(UsbBus::new(parts.usb, cx.local.ep_memory));
        let serial = SerialPort::new_with_store(usb_bus, [0; 256], [0; 1024]);
        let usb_dev = match UsbDeviceBuilder::new(usb_bus, UsbVidPid(0x16c0, 0x27dd))
            .device_class(usbd_serial::USB_CLASS_CDC)
            .strings(&[StringDescriptors::default()
                .manufacturer("sandjumper")
                .product("sandjumper rig")
                .serial_number(board::serial_number(cx.local.serial_number))])
        {
            Ok(builder) => builder.build(),
            Err(_) => defmt::panic!("USB string descriptors rejected"),
        };

        let (inbound_tx, inbound_rx) = cx.local.inbound.split();
        let (outbound_tx, outbound_rx) = cx.local.outbound.split();
        let (samples_tx, samples_rx) = cx.local.samples.split();

        io.start_ticking(board::TICK_HZ);
        defmt::info!(
            "sandjumper firmware: STM32F407, tick {} Hz, budget {} cycles, reset cause {}, brown-out level {}",
            board::TICK_HZ,
            board::TICK_BUDGET_CYCLES,
            reset_cause,
            board::brown_out_level()
        );
        (
            Shared {},
            Local {
                io,
                rig,
                inbound_rx,
                outbound_tx,
                samples_tx,
                inbound_tx,
                outbound_rx,
                samples_rx,
                usb_dev,
                serial,
                decoder: FrameDecoder::new(),
            },
        )
    }

    #[task(binds = TIM7, priority = 3, local = [
        io, rig, inbound_rx, outbound_tx, samples_tx,
        timing: TickTiming = TickTiming::Unknown,
        lockstep: bool = false,
    ])]
    fn control_tick(cx: control_tick::Context) {
        let start = DWT::cycle_count();
        let control_tick::LocalResources {
            io,
            rig,
            inbound_rx,
            outbound_tx,
            samples_tx,
            timing,
            lockstep,
            ..
        } = cx.local;
        io.acknowledge_tick();
        rig.note_tick_start(start);
        if crate::inject_f407::INJECTED.is_some() {
            crate::inject_f407::at_tick(rig.status().tick);
        }
        // The sensors first, at a fixed time after the tick starts, whatever the host sent.
        let encoder_raw = io.encoder_count();
        let current_code = io.current_sense_code();
        // The emergency stop every tick, whatever else is connected (lockstep included).
        rig.set_emergency_stop_loop(io.emergency_stop_open());
        let real_bed = io.bed_inputs();
        if let Some(bed) = real_bed {
            rig.set_bed_inputs(bed);
        }
        let fault_before = rig.fault();
        let dropped = INBOUND_DROPPED.swap(0, Ordering::Relaxed);
        if dropped > 0 {
            rig.note_frames_dropped(dropped);
        }
        // At most one host frame per tick, and only when its answer (plus a fault report) has
        // room to leave. A sensor frame (lockstep) is the tick's input and is taken now; a
        // command waits until the outputs are written, so the DAC update and the camera edge
        // come at the same time in every tick whatever the host sent.
        let mut ticked = false;
        let mut command = None;
        let room = outbound_tx.capacity() - outbound_tx.len();
        if room >= 2 {
            match inbound_rx.peek() {
                None => {}
                Some(Inbound::Message(HostMessage::Sensor(_))) => {
                    if let Some(Inbound::Message(HostMessage::Sensor(mut frame))) =
                        inbound_rx.dequeue()
                    {
                        *lockstep = true;
                        rig.note_frame_ok();
                        // The simulated bed stands in for the real one, except a real
                        // harness pulled out, which still stops (the real emergency stop's
                        // loop reaches the core above, in every mode).
                        if let Some(real) = real_bed {
                            let mut bed = frame.bed.unwrap_or(real);
                            bed.emergency_stop |= real.emergency_stop;
                            frame.bed = Some(bed);
                        }
                        let actuator = rig.lockstep(&frame, *timing);
                        send(outbound_tx, rig, RigMessage::Actuator(actuator));
                        ticked = true;
                    }
                }
                Some(_) => command = inbound_rx.dequeue(),
            }
        }

        if *lockstep {
            // Hardware-in-the-loop: the simulated plant is driven, never the real motor, and
            // the real bed apparatus stays off.
            io.set_drive(rig.drive_calibration().zero_code, false);
            io.set_camera_trigger(false);
            io.set_bed(&BedOutputs::default());
            if !ticked {
                // A timer tick without a sensor frame: the core counts the silence.
                rig.lockstep_silent_period();
            }
        } else {
            let input = TickInput {
                encoder_raw,
                current_a: Some(drive::current_from_code(current_code)),
                timing: *timing,
            };
            let out = rig.tick(&input);
            let code = rig.drive_calibration().force_to_code(out.force_n);
            io.set_drive(code, out.drive_enabled);
            io.set_camera_trigger(out.camera_trigger);
            io.set_bed(&out.bed);
            io.start_current_sample();
            io.set_leds(out.drive_enabled, out.fault.is_some());
            ticked = true;
        }
        match command {
            Some(Inbound::Rejected) => rig.note_frame_rejected(),
            Some(Inbound::Message(HostMessage::Command { id, command })) => {
                let reply = link::reply_to(rig, id, &command);
                send(outbound_tx, rig, reply);
            }
            _ => {}
        }
        if let Some(report) = link::newly_latched(rig, fault_before) {
            send(outbound_tx, rig, report);
        }

        // Telemetry: as many records as the link's queue takes; the rest wait in the core's
        // queue (whose overflow the core counts).
        while samples_tx.ready() {
            let Some(record) = rig.samples().pop() else {
                break;
            };
            // Cannot fail: `ready` checked.
            let _ = samples_tx.enqueue(record);
        }
        io.feed_watchdog();
        io.toggle_heartbeat();
        if samples_tx.len() >= SAMPLE_BATCH || !outbound_tx.is_empty() {
            rtic::pend(Interrupt::OTG_FS);
        }
        if ticked {
            *timing = TickTiming::Cycles(DWT::cycle_count().wrapping_sub(start));
        }
    }

    /// Queues a message for the link; if the queue is full it is counted in the core's
    /// `frames_dropped`, never waited for (and never logged from the tick).
    fn send<const Q: usize>(
        outbound: &mut Producer<'static, RigMessage>,
        rig: &mut Rig<Q>,
        msg: RigMessage,
    ) {
        if outbound.enqueue(msg).is_err() {
            rig.note_frames_dropped(1);
        }
    }

    #[task(binds = OTG_FS, priority = 1, local = [
        usb_dev, serial, decoder, inbound_tx, outbound_rx, samples_rx,
        tx: heapless::Vec<u8, MAX_FRAME> = heapless::Vec::new(),
        tx_sent: usize = 0,
    ])]
    fn host_link(cx: host_link::Context) {
        let host_link::LocalResources {
            usb_dev,
            serial,
            decoder,
            inbound_tx,
            outbound_rx,
            samples_rx,
            tx,
            tx_sent,
            ..
        } = cx.local;
        usb_dev.poll(&mut [serial]);
        // The host has the port open: it configured the device and set DTR (a bus reset clears
        // it). Nothing is written to the data endpoint otherwise: a write during a bus reset
        // re-enables the IN endpoint the reset just disabled, and the driver's configure
        // cannot disable it again (EPENA is set-only), which left it NAKing empty forever (found
        // on the virtual board). A frame cut off by the reset is dropped and counted.
        let open = serial.dtr();
        if !open && !tx.is_empty() {
            if *tx_sent < tx.len() {
                INBOUND_DROPPED.fetch_add(1, Ordering::Relaxed);
            }
            tx.clear();
            *tx_sent = 0;
        }

        // Receive: decode, queue for the tick in arrival order.
        let mut buf = [0u8; 64];
        while let Ok(n @ 1..) = serial.read(&mut buf) {
            for &byte in &buf[..n] {
                let inbound = match decoder.push::<HostMessage>(byte) {
                    None => continue,
                    Some(Ok(msg)) => Inbound::Message(msg),
                    Some(Err(_)) => Inbound::Rejected,
                };
                if inbound_tx.enqueue(inbound).is_err() {
                    // The core counts it (next tick) in `frames_dropped`.
                    INBOUND_DROPPED.fetch_add(1, Ordering::Relaxed);
                }
            }
        }

        // Transmit: finish the frame in flight, then replies/faults/actuator frames, then
        // sample batches; stop when the USB buffer is full.
        if !open {
            // Telemetry for nobody: discarded, so a host that opens the port gets the samples
            // from then on, not a stale queue and a gap (Status's samples_produced counts them).
            while samples_rx.dequeue().is_some() {}
            return;
        }
        loop {
            if *tx_sent < tx.len() {
                match serial.write(&tx[*tx_sent..]) {
                    Ok(n) => *tx_sent += n,
                    Err(_) => break,
                }
                continue;
            }
            let msg = if let Some(msg) = outbound_rx.dequeue() {
                msg
            } else if samples_rx.len() >= SAMPLE_BATCH {
                let mut batch = None;
                link::send_sample_batches(
                    || samples_rx.dequeue(),
                    SAMPLE_BATCH,
                    false,
                    |m| batch = Some(m),
                );
                match batch {
                    Some(msg) => msg,
                    None => break,
                }
            } else {
                break;
            };
            tx.clear();
            *tx_sent = 0;
            // Every RigMessage fits MAX_FRAME by the protocol's construction; a failure drops
            // that message, counted in the core's `frames_dropped`.
            let _ = tx.resize_default(MAX_FRAME);
            match encode_frame(&msg, tx) {
                Ok(n) => tx.truncate(n),
                Err(_) => {
                    tx.clear();
                    INBOUND_DROPPED.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
    }
}
