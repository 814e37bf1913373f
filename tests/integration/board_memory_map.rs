//! The root `memory.x` must describe the reference board (STM32F407): a wrong
//! origin or length links firmware that faults at reset or overruns RAM.

fn region(text: &str, name: &str) -> Option<(u64, u64)> {
    let line = text
        .lines()
        .map(str::trim)
        .find(|l| l.split_whitespace().next() == Some(name))?;
    let origin = line
        .split("ORIGIN")
        .nth(1)?
        .split(['=', ','])
        .nth(1)?
        .trim();
    let length = line.split("LENGTH").nth(1)?.split('=').nth(1)?.trim();
    let origin = u64::from_str_radix(origin.trim_start_matches("0x"), 16).ok()?;
    let length = match length.strip_suffix('K') {
        Some(k) => k.parse::<u64>().ok()? * 1024,
        None => length.parse().ok()?,
    };
    Some((origin, length))
}

#[test]
fn memory_x_describes_the_stm32f407() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/memory.x"))
        .expect("memory.x at the workspace root");
    assert_eq!(region(&text, "FLASH"), Some((0x0800_0000, 1024 * 1024)));
    assert_eq!(region(&text, "RAM"), Some((0x2000_0000, 128 * 1024)));
    assert_eq!(region(&text, "CCMRAM"), Some((0x1000_0000, 64 * 1024)));
}
