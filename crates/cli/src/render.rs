//! `faceanim render`: a character to PNG, one pose or a contact sheet of every blendshape.

use std::path::PathBuf;

use clap::Args;

/// `faceanim render`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct RenderArgs {
    /// The character (default: the built-in head).
    pub(crate) character: Option<PathBuf>,
    /// Where to write the PNG (`.png`; - for standard output).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Blendshape weights as NAME=VALUE pairs separated by commas (ARKit spellings match).
    #[arg(long, value_delimiter = ',')]
    pub(crate) weights: Vec<String>,
    /// A labelled grid of the neutral face and each blendshape at weight 1 instead.
    #[arg(long, conflicts_with = "weights")]
    pub(crate) sheet: bool,
    /// Image size in pixels (for a sheet, each cell's size, at most 512).
    #[arg(long, default_value_t = 512)]
    pub(crate) size: u32,
}

/// `faceanim render`.
pub(crate) fn run(args: &RenderArgs) -> anyhow::Result<()> {
    // The picture is a PNG: another ending would name it as what it is not (a `.jpg` that
    // holds a PNG). Checked, with its folder, before the character is read.
    let path = &args.output;
    anyhow::ensure!(
        faceanim_files::is_stdout(path)
            || path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png")),
        "{}: render writes a PNG picture: name it .png (or - for standard output)",
        path.display()
    );
    faceanim_files::check_output(path)?;
    let character = crate::input::load_or_default(args.character.as_deref())?.character;
    let size = args.size;
    anyhow::ensure!(
        (16..=4096).contains(&size),
        "--size must be between 16 and 4096 pixels, got {size}"
    );
    let image = if args.sheet {
        faceanim_render::contact_sheet(&character, size.min(512))
    } else {
        let mut w = vec![0.0; character.blendshapes().len()];
        for pair in &args.weights {
            let (name, value) = pair
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--weights: '{pair}' is not NAME=VALUE"))?;
            let name = name.trim();
            let value: f32 = value
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("--weights: '{value}' is not a number"))?;
            anyhow::ensure!(
                value.is_finite(),
                "--weights: '{value}' is not a finite number"
            );
            if let Some(id) = character.find_blendshape(name) {
                w[id.index()] = value;
                continue;
            }
            // An ARKit channel in any spelling: the shapes that answer to it by name, as
            // `info` lists them (browInnerUp → browInnerUp_L and _R).
            let channel = faceanim_rig::names::arkit_name(name).ok_or_else(|| {
                anyhow::anyhow!(
                    "--weights: '{name}' is neither a blendshape of {} nor an ARKit channel",
                    character.name()
                )
            })?;
            let driven = character
                .name_map()
                .weights_from_channels(|c| if c == channel { value } else { 0.0 });
            let mut any = false;
            for (weight, from) in w.iter_mut().zip(driven) {
                if from != 0.0 {
                    *weight = from;
                    any = true;
                }
            }
            anyhow::ensure!(
                any || value == 0.0,
                "--weights: no blendshape of {} answers to the ARKit channel {channel} by name \
                 (`faceanim info` lists what drives what; `faceanim retarget` maps it)",
                character.name()
            );
        }
        let pose = character.pose(&w);
        let camera = faceanim_render::Camera::front(&character.head_bounds(), 0.75);
        let appearance = faceanim_render::Appearance::of(&character);
        for warning in appearance.warnings() {
            eprintln!("warning: {warning}");
        }
        faceanim_render::render(&character, &pose, &camera, &appearance, size)
    };
    faceanim_files::write_output(&args.output, &image.to_png()?)?;
    eprintln!(
        "wrote {} ({}×{})",
        args.output.display(),
        image.width,
        image.height
    );
    Ok(())
}
