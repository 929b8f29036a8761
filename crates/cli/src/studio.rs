//! `faceanim studio`: serves the page on a local port for a character and its project.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

/// `faceanim studio`'s arguments.
#[derive(Debug, Args)]
pub(crate) struct StudioArgs {
    /// The character: .glb, .gltf, or a folder of OBJ files (default: the built-in head).
    pub(crate) character: Option<PathBuf>,
    /// Port on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 7878)]
    pub(crate) port: u16,
    /// Open the page in the default browser.
    #[arg(long)]
    pub(crate) open: bool,
    /// The project file (strokes JSON) to open and save.
    #[arg(long)]
    pub(crate) project: Option<PathBuf>,
    /// The character's adapter for capture mode: read if it exists, written when trained
    /// from the page.
    #[arg(long)]
    pub(crate) adapter: Option<PathBuf>,
    /// Listen for VMC (Waidayo, iFacialMocap's Windows edition, another performer; for the
    /// phone apps' own protocols see --phone)
    /// on this UDP port, all interfaces, or on ADDR:PORT; the Capture tab's VMC button shows
    /// it live and records takes from it. Without a value: 39539, VMC's default.
    #[arg(long, num_args = 0..=1, default_missing_value = "39539", value_name = "[ADDR:]PORT")]
    pub(crate) vmc_listen: Option<String>,
    /// Send the live face (webcam, phone or microphone) and what the page plays over VMC to a
    /// marionette (VSeeFace, Warudo, VNyan, Unity, Unreal) at HOST:PORT.
    #[arg(long, value_name = "HOST:PORT")]
    pub(crate) vmc_send: Option<String>,
    /// The names --vmc-send uses: the character's own, ARKit's 52 (perfect sync) or VRM 0.x's
    /// presets; under arkit and vrm what the character's shapes cannot make goes out from the
    /// captured face's own ARKit values.
    #[arg(long, value_enum, default_value_t = crate::stream::NameChoice::Own)]
    pub(crate) vmc_names: crate::stream::NameChoice,
    #[command(flatten)]
    pub(crate) phone: crate::phone::PhoneArgs,
}

/// `faceanim studio`.
pub(crate) fn run(args: StudioArgs) -> anyhow::Result<()> {
    let StudioArgs {
        character: character_file,
        port,
        open,
        project,
        adapter,
        vmc_listen,
        vmc_send,
        vmc_names,
        phone,
    } = args;
    let vmc_listen = vmc_listen
        .map(|a| crate::stream::listen_address(&a))
        .transpose()?
        .map(|address| faceanim_studio::capture::Listen {
            address,
            source: faceanim_live::Source::vmc(),
            settings_file: None,
        });
    let vmc = faceanim_studio::capture::VmcConfig {
        listen: phone.listen()?.or(vmc_listen),
        send: vmc_send
            .map(|a| crate::stream::destination(&a).map(|d| (d, vmc_names.into())))
            .transpose()?,
    };
    let character = crate::input::load_or_default(character_file.as_deref())?.character;
    let project_path = match project {
        Some(path) => path,
        None => std::env::current_dir()
            .context("finding the current folder for the project file")?
            .join(format!(
                "{}.faceanim.json",
                crate::input::safe_file_name(character.name())
            )),
    };
    // The adapter lives beside the character file; the built-in head's beside the project.
    let adapter_path = adapter.unwrap_or_else(|| {
        faceanim_adapt::default_adapter_path(
            character_file
                .as_deref()
                .and_then(std::path::Path::parent)
                .or_else(|| project_path.parent()),
            character.name(),
        )
    });
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the server runtime")?;
    let served = runtime.block_on(async move {
        let (listener, address) = faceanim_studio::bind(port).await?;
        let url = format!("http://{address}/");
        outln!(
            "faceanim studio: {url}  (character: {}, project: {})",
            character.name(),
            project_path.display()
        );
        if open {
            let opener = if cfg!(target_os = "macos") {
                "open"
            } else {
                "xdg-open"
            };
            if let Err(e) = std::process::Command::new(opener).arg(&url).spawn() {
                eprintln!("warning: could not open a browser ({opener}: {e}); open {url} yourself");
            }
        }
        faceanim_studio::serve(
            faceanim_studio::Config {
                adapter_path,
                character,
                project_path,
                vmc,
            },
            listener,
        )
        .await?;
        anyhow::Ok(())
    });
    // Stopped (Ctrl-C, SIGTERM): its scratch folder is gone and its work saved; work still on
    // the runtime's blocking threads (a recording being heard) is not waited for.
    runtime.shutdown_background();
    served
}
