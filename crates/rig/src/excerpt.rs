//! User text quoted in messages: a name or a value from a file is shown whole when short, and
//! cut (on a character boundary, with `…`) when long, so that a 10 MB key never fills a terminal
//! or an HTTP answer. The one rule every crate's messages follow.

use std::borrow::Cow;

/// The longest text quoted whole, in characters.
pub const QUOTED_CHARS: usize = 60;

/// `text` as a message quotes it: whole up to [`QUOTED_CHARS`] characters, else its first 40
/// characters and `…` with the length. Control characters are shown as `?`, so that a name
/// cannot move the cursor or clear a terminal.
///
/// ```
/// use faceanim_rig::excerpt;
/// assert_eq!(excerpt("jawOpen"), "jawOpen");
/// let long = "x".repeat(10_000);
/// assert_eq!(excerpt(&long), format!("{}… (10000 characters)", "x".repeat(40)));
/// assert_eq!(excerpt("a\u{1b}[2Jb"), "a?[2Jb");
/// ```
#[must_use]
pub fn excerpt(text: &str) -> Cow<'_, str> {
    let clean = |s: &str| -> String {
        s.chars()
            .map(|c| if c.is_control() { '?' } else { c })
            .collect()
    };
    let count = text.chars().count();
    if count <= QUOTED_CHARS {
        if text.chars().any(char::is_control) {
            Cow::Owned(clean(text))
        } else {
            Cow::Borrowed(text)
        }
    } else {
        let cut = text.char_indices().nth(40).map_or(text.len(), |(i, _)| i);
        Cow::Owned(format!("{}… ({count} characters)", clean(&text[..cut])))
    }
}
