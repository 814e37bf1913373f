//! The rig firmware on the STM32F407: RTIC 2.
//!
//! Priorities (higher preempts lower):
//! - 3 `control_tick` (TIM7 at the tick rate): encoder -> core tick -> drive -> camera trigger,
//!   cycle-counted; owns the core and the rig peripherals outright (no locks).
//! - 1 `host_link` (OTG_FS interrupt, also pended by the tick): USB CDC, command decoding,
//!   telemetry draining. It talks to the tick only through lock-free single-producer
//!   single-consumer queues, so nothing it does can delay the tick.

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use crate::board::f407::{self as board, Rig};
    use cortex_m::peripheral::DWT;
    use stm32f4xx_hal::otg_fs::{UsbBus, UsbBusType};
    use usb_device::prelude::*;
    use usbd_serial::SerialPort;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        rig: Rig,
        usb_dev: UsbDevice<'static, UsbBusType>,
        usb_serial: SerialPort<'static, UsbBusType>,
    }

    #[init(local = [
        ep_memory: [u32; 1024] = [0; 1024],
        usb_bus: Option<usb_device::bus::UsbBusAllocator<UsbBusType>> = None,
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut core = cx.core;
        core.DCB.enable_trace();
        core.DWT.enable_cycle_counter();
        let parts = board::init(cx.device);
        let mut rig = parts.rig;

        let usb_bus = cx
            .local
            .usb_bus
            .insert(UsbBus::new(parts.usb, cx.local.ep_memory));
        let usb_serial = SerialPort::new(usb_bus);
        let usb_dev = UsbDeviceBuilder::new(usb_bus, UsbVidPid(0x16c0, 0x27dd))
            .device_class(usbd_serial::USB_CLASS_CDC)
            .strings(&[StringDescriptors::default()
                .manufacturer("sandjumper")
                .product("sandjumper rig")
                .serial_number("F407")])
            .expect("one string descriptor set")
            .build();

        rig.start_ticking(board::TICK_HZ);
        defmt::info!("sandjumper firmware: STM32F407, tick {} Hz", board::TICK_HZ);
        (
            Shared {},
            Local {
                rig,
                usb_dev,
                usb_serial,
            },
        )
    }

    #[task(binds = TIM7, priority = 3, local = [rig])]
    fn control_tick(cx: control_tick::Context) {
        let start = DWT::cycle_count();
        let rig = cx.local.rig;
        rig.acknowledge_tick();
        let _encoder = rig.encoder_count();
        let _current = rig.current_sense_code();
        rig.set_drive(crate::drive::ZERO_FORCE_CODE, false);
        rig.set_camera_trigger(false);
        rig.start_current_sample();
        rig.feed_watchdog();
        let _cycles = DWT::cycle_count().wrapping_sub(start);
        rtic::pend(stm32f4xx_hal::pac::Interrupt::OTG_FS);
    }

    #[task(binds = OTG_FS, priority = 1, local = [usb_dev, usb_serial])]
    fn host_link(cx: host_link::Context) {
        let mut buf = [0u8; 64];
        if cx.local.usb_dev.poll(&mut [cx.local.usb_serial]) {
            let _ = cx.local.usb_serial.read(&mut buf);
        }
    }
}
