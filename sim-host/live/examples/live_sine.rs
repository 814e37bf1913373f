//! A live view of a made-up run: a page at http://127.0.0.1:PORT/ showing one channel, a sine,
//! for two seconds at real time, then kept up for five seconds.
//!
//! Run it with `cargo run -p sandjumper-live --example live_sine` and open the printed URL.

use sandjumper_live::{Event, LiveConfig, LiveView};

fn main() -> Result<(), String> {
    let config = LiveConfig {
        addr: "127.0.0.1:0".into(),
        linger: Some(5.0),
        ..LiveConfig::default()
    };
    let mut view = LiveView::start(&config, &["p_mm"])?;
    for line in view.addresses() {
        println!("{line}");
    }
    view.bus().event(Event::RunStarted {
        title: "a sine, 5 Hz".into(),
        t_s: 0.0,
    });
    for k in 0..20_000 {
        let t_s = f64::from(k) * 1e-4;
        let p_mm = 10.0 * (std::f64::consts::TAU * 5.0 * t_s).sin();
        view.bus().sample(t_s, &[p_mm]);
        view.keep_pace(t_s);
    }
    view.end(2.0, "completed".into(), true);
    view.wait_until_shown();
    println!("{}", view.lingering());
    view.linger_until(&|| false);
    Ok(())
}
