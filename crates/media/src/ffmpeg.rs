//! What ffmpeg says, in words for the user: its messages name codecs, filter graphs and
//! atoms; the user needs to know what is wrong with the file and what to do. The one table
//! every reader of ffmpeg's output (video here, sound in `faceanim-speech`) translates by.

/// ffmpeg's phrases (as they appear in its error lines) and what to tell the user instead.
const PHRASES: [(&str, &str); 13] = [
    (
        "Invalid data found when processing input",
        "not a video, sound or picture that ffmpeg can read (damaged, or another kind of file)",
    ),
    (
        "moov atom not found",
        "the file is cut short: its index is missing (a recording that was not finished)",
    ),
    (
        "End of file",
        "the file ends too early: it is cut short, or still being written",
    ),
    (
        "Error configuring filter graph",
        "its frames could not be converted (an unusual size or pixel format); re-encode it, for example: ffmpeg -i IN -pix_fmt yuv420p OUT.mp4",
    ),
    (
        "Error reinitializing filters",
        "its frames change size or format part-way; re-encode it, for example: ffmpeg -i IN -pix_fmt yuv420p OUT.mp4",
    ),
    (
        "Failed to inject frame into filter network",
        "its frames change size or format part-way; re-encode it, for example: ffmpeg -i IN -pix_fmt yuv420p OUT.mp4",
    ),
    (
        "Could not find codec parameters",
        "its format could not be worked out (too short, or damaged)",
    ),
    (
        "Decoding requested, but no decoder found",
        "it is in a format this ffmpeg cannot decode; convert it to MP4 (H.264) or WAV",
    ),
    (
        "Unknown decoder",
        "it is in a format this ffmpeg cannot decode; convert it to MP4 (H.264) or WAV",
    ),
    ("Permission denied", "permission denied: it cannot be read"),
    ("No such file or directory", "no such file"),
    (
        "does not contain any stream",
        "it holds no video or sound stream",
    ),
    (
        "matches no streams",
        "it holds no stream of the kind needed",
    ),
];

/// What to tell the user for ffmpeg's error output `said` (several lines): the translation
/// of the first phrase ffmpeg is known to use, else ffmpeg's last line (cut when long), said to
/// be ffmpeg's.
///
/// ```
/// use faceanim_media::ffmpeg::explain;
/// assert_eq!(
///     explain("[fatal] in.mp4: End of file"),
///     "the file ends too early: it is cut short, or still being written"
/// );
/// assert_eq!(explain("odd words"), "ffmpeg could not read it: odd words");
/// ```
#[must_use]
pub fn explain(said: &str) -> String {
    if let Some((_, meaning)) = PHRASES.iter().find(|(phrase, _)| said.contains(phrase)) {
        return (*meaning).to_owned();
    }
    let last = said
        .lines()
        .map(str::trim)
        .rfind(|l| !l.is_empty())
        .unwrap_or("it stopped without saying why");
    // Drop the log level ffmpeg prints with -v level: `[error] …`.
    let last = match last.strip_prefix('[').and_then(|r| r.split_once("] ")) {
        Some((_, rest)) => rest,
        None => last,
    };
    let cut: String = last.chars().take(200).collect();
    format!("ffmpeg could not read it: {cut}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ffmpeg_words_become_what_to_do() {
        assert!(explain("[error] Error configuring filter graph").contains("re-encode it"));
        assert!(
            explain("x.mp4: Invalid data found when processing input").starts_with("not a video")
        );
        assert_eq!(
            explain("[error] something new\n"),
            "ffmpeg could not read it: something new"
        );
        assert_eq!(
            explain(""),
            "ffmpeg could not read it: it stopped without saying why"
        );
        assert!(explain(&"z".repeat(5000)).chars().count() < 240);
    }
}
