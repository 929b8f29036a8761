//! `faceanim eval`: a clip against a reference clip (DTW distance, jitter, MAE).

use std::path::PathBuf;

use clap::Args;

/// `faceanim eval`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    /// The clip to judge (a clip JSON, or an animation file as `export --clip` reads them).
    pub(crate) a: PathBuf,
    /// The reference clip (the same kinds).
    pub(crate) b: PathBuf,
    /// Print machine-readable JSON.
    #[arg(long)]
    pub(crate) json: bool,
}
/// `faceanim eval`.
pub(crate) fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let (clip_a, clip_b) = (crate::input::clip(&args.a)?, crate::input::clip(&args.b)?);
    let result = faceanim_anim::metrics::compare(&clip_a, &clip_b);
    if args.json {
        outln!("{}", serde_json::to_string(&result)?);
    } else {
        outln!(
            "DTW distance        {:.4} ({:.4} per frame)",
            result.dtw,
            result.dtw_per_frame
        );
        outln!(
            "jitter (RMS change) {:.4} vs {:.4} (difference {:+.4})",
            result.jitter_a,
            result.jitter_b,
            result.jitter_diff
        );
        match result.mae {
            Some(mae) => outln!("MAE                 {mae:.4}"),
            None => {
                outln!("MAE                 n/a (the clips differ in frames or names)")
            }
        }
    }
    Ok(())
}
