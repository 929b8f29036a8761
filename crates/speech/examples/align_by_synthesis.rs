//! Aligns a transcript to a recording by synthesis and prints the phones as JSON lines
//! (`{"label": …, "start": …, "end": …}`): `cargo run -p faceanim-speech --example
//! align_by_synthesis -- SPEECH.wav LANGUAGE TEXT`. For measuring the alignment alone, on any
//! language, English included (which `faceanim lipsync` aligns with the recogniser).
use std::io::Write as _;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let usage = "usage: align_by_synthesis SPEECH LANGUAGE TEXT";
    let speech = args.next().ok_or(usage)?;
    let language = args.next().ok_or(usage)?;
    let text = args.next().ok_or(usage)?;
    let sound = faceanim_speech::Sound::read(std::path::Path::new(&speech))?;
    let phones = faceanim_speech::synthesis::align(&sound, &text, &language)?;
    let mut out = std::io::stdout().lock();
    for phone in phones {
        writeln!(out, "{}", serde_json::to_string(&phone)?)?;
    }
    Ok(())
}
