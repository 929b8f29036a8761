//! `faceanim render`: a character to PNG, one pose or a contact sheet of every blendshape.

use std::path::PathBuf;

use clap::Args;

/// `faceanim render`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct RenderArgs {
    /// The character (default: the built-in head).
    pub(crate) character: Option<PathBuf>,
    /// Where to write the PNG.
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
            let id = character.find_blendshape(name.trim()).ok_or_else(|| {
                anyhow::anyhow!(
                    "--weights: '{name}' is not a blendshape of {}",
                    character.name()
                )
            })?;
            let value: f32 = value
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("--weights: '{value}' is not a number"))?;
            anyhow::ensure!(
                value.is_finite(),
                "--weights: '{value}' is not a finite number"
            );
            w[id.index()] = value;
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
