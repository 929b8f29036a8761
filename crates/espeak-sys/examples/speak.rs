//! Speaks a line and prints its phones with their times: `cargo run -p faceanim-espeak-sys
//! --example speak -- VOICE TEXT [OUT.raw]` (the sound, when asked, as raw 16-bit samples).
use std::io::Write as _;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let voice = args.next().ok_or("usage: speak VOICE TEXT [OUT.raw]")?;
    let text = args.next().ok_or("usage: speak VOICE TEXT [OUT.raw]")?;
    let spoken = faceanim_espeak_sys::speak(&text, &voice, None)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{} samples at {} Hz; words at {:?} ms",
        spoken.samples.len(),
        spoken.sample_rate,
        spoken.words_ms
    )?;
    for phone in &spoken.phones {
        writeln!(
            out,
            "{:>6} ms  word {:>2}  {}",
            phone.start_ms, phone.word, phone.ipa
        )?;
    }
    if let Some(path) = args.next() {
        let bytes: Vec<u8> = spoken
            .samples
            .iter()
            .flat_map(|s| s.to_le_bytes())
            .collect();
        std::fs::write(path, bytes)?;
    }
    Ok(())
}
