//! `faceanim studio --phone …`: which phone tracker the studio listens to, where, how its
//! angles are written, and where its calibrated neutral is kept between runs.

use std::net::{SocketAddr, ToSocketAddrs as _};
use std::path::PathBuf;

use anyhow::Context as _;
use faceanim_live::phone::{AngleUnit, Protocol};
use faceanim_live::{Source, SourceSettings};
use faceanim_studio::capture::Listen;

/// The phone apps the studio reads in their own protocols.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum PhoneApp {
    /// Epic's Live Link Face (ARKit mode), UDP 11111: set this machine's address in the app.
    #[value(alias = "livelink")]
    LiveLinkFace,
    /// iFacialMocap, MeowFace, Facemotion3d, UDP 49983: give --phone-address; the studio
    /// sends the handshake.
    #[value(alias = "meowface", alias = "facemotion3d")]
    Ifacialmocap,
    /// VTube Studio's phone app, UDP 21412: give --phone-address; the studio asks for frames
    /// every second.
    #[value(alias = "vts")]
    VtubeStudio,
}

impl From<PhoneApp> for Protocol {
    fn from(app: PhoneApp) -> Protocol {
        match app {
            PhoneApp::LiveLinkFace => Protocol::LiveLinkFace,
            PhoneApp::Ifacialmocap => Protocol::IFacialMocap,
            PhoneApp::VtubeStudio => Protocol::VTubeStudio,
        }
    }
}

/// How a phone's angles are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Unit {
    /// Degrees.
    Degrees,
    /// Radians.
    Radians,
}

impl From<Unit> for AngleUnit {
    fn from(unit: Unit) -> AngleUnit {
        match unit {
            Unit::Degrees => AngleUnit::Degrees,
            Unit::Radians => AngleUnit::Radians,
        }
    }
}

/// The phone's arguments.
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct PhoneArgs {
    /// Listen to a phone face tracker in its own protocol, on all interfaces (the page shows
    /// this machine's addresses to type into the app); the Capture tab shows it live, records
    /// takes from it and sends it on with --vmc-send.
    #[arg(long, value_enum, conflicts_with = "vmc_listen")]
    pub(crate) phone: Option<PhoneApp>,
    /// The phone's address, HOST or HOST:PORT, for the apps that must be asked for frames
    /// (iFacialMocap, VTube Studio).
    #[arg(long, value_name = "HOST[:PORT]", requires = "phone")]
    pub(crate) phone_address: Option<String>,
    /// The UDP port to listen on (default: the app's own: 11111, 49983, 21412).
    #[arg(long, value_name = "PORT", requires = "phone")]
    pub(crate) phone_port: Option<u16>,
    /// The unit of the phone's head and eye angles (default: the app's; radians for Live Link
    /// Face, degrees for the others); kept with the neutral.
    #[arg(long, value_enum, requires = "phone")]
    pub(crate) phone_angles: Option<Unit>,
    /// Where the phone's settings (angle units and the neutral face the page's Neutral button
    /// takes) are kept between runs (default: faceanim/phone-APP.json in the user's
    /// configuration folder).
    #[arg(long, value_name = "FILE", requires = "phone")]
    pub(crate) phone_settings: Option<PathBuf>,
}

impl PhoneArgs {
    /// What the studio listens to, when a phone was given.
    pub(crate) fn listen(self) -> anyhow::Result<Option<Listen>> {
        let Some(app) = self.phone else {
            return Ok(None);
        };
        let protocol = Protocol::from(app);
        let phone = match (&self.phone_address, protocol.asks_the_phone()) {
            (Some(text), _) => Some(phone_address(text, protocol)?),
            (None, true) => anyhow::bail!(
                "--phone {}: give the phone's address with --phone-address (shown in the app), \
                 so that the studio can ask it for frames",
                protocol.label()
            ),
            (None, false) => None,
        };
        let settings_file = match self.phone_settings {
            Some(path) => Some(path),
            None => config_folder().map(|folder| {
                folder
                    .join("faceanim")
                    .join(format!("phone-{}.json", app_slug(protocol)))
            }),
        };
        let mut settings = match &settings_file {
            Some(path) if path.exists() => {
                let bytes = faceanim_files::read_bytes(path)?;
                serde_json::from_slice::<SourceSettings>(&bytes).with_context(|| {
                    format!(
                        "{}: not faceanim's phone settings (delete it to start again)",
                        path.display()
                    )
                })?
            }
            _ => SourceSettings::of(protocol),
        };
        if let Some(unit) = self.phone_angles {
            settings.head_unit = unit.into();
            settings.eye_unit = unit.into();
        }
        Ok(Some(Listen {
            address: SocketAddr::from((
                [0, 0, 0, 0],
                self.phone_port.unwrap_or(protocol.default_port()),
            )),
            source: Source {
                protocol,
                phone,
                settings,
            },
            settings_file,
        }))
    }
}

fn app_slug(protocol: Protocol) -> &'static str {
    match protocol {
        Protocol::Vmc => "vmc",
        Protocol::LiveLinkFace => "live-link-face",
        Protocol::IFacialMocap => "ifacialmocap",
        Protocol::VTubeStudio => "vtube-studio",
    }
}

/// The phone's address: `HOST` (the app's own port) or `HOST:PORT`.
fn phone_address(text: &str, protocol: Protocol) -> anyhow::Result<SocketAddr> {
    let port = match protocol {
        Protocol::VTubeStudio => faceanim_live::phone::VTUBE_STUDIO_PORT,
        other => other.default_port(),
    };
    let with_port = if text.contains(':') && !text.starts_with('[') && text.matches(':').count() > 1
    {
        // A bare IPv6 address.
        format!("[{text}]:{port}")
    } else if text.contains(':') {
        text.to_owned()
    } else {
        format!("{text}:{port}")
    };
    with_port
        .to_socket_addrs()
        .with_context(|| format!("--phone-address {text}: not a HOST or HOST:PORT"))?
        .next()
        .with_context(|| format!("--phone-address {text}: no address"))
}

/// The user's configuration folder: `$XDG_CONFIG_HOME` or `~/.config` (Linux),
/// `~/Library/Application Support` (macOS), `%APPDATA%` (Windows).
fn config_folder() -> Option<PathBuf> {
    let from = |name: &str| {
        std::env::var_os(name)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    if cfg!(windows) {
        return from("APPDATA");
    }
    if cfg!(target_os = "macos") {
        return from("HOME").map(|h| h.join("Library/Application Support"));
    }
    from("XDG_CONFIG_HOME").or_else(|| from("HOME").map(|h| h.join(".config")))
}
