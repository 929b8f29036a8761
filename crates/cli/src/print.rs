//! Printing to standard output that returns its error, so that a reader that went away (`faceanim
//! … | head`) ends the command quietly instead of panicking.

/// `println!` that returns the error (a reader that went away: `faceanim … | head`) instead of
/// panicking; `main` ends quietly on a broken pipe, as ripgrep does.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

/// `print!` that returns the error; see [`outln`].
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)?
    }};
}
