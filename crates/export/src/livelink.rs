//! Live Link Face CSV: the file Epic's Live Link Face app records, which Unreal, Blender
//! add-ons and MetaHuman tools import. Columns: `Timecode`, `BlendShapeCount` (61), the 52
//! ARKit blendshapes in ARKit's `ARFaceAnchor` order ([`ARKIT_52`]; Unreal's
//! `EARFaceBlendShape` has the same), then head
//! yaw, pitch, roll and each eye's yaw, pitch, roll in radians.
//!
//! Clip columns are read back into ARKit's channels by faceanim's name table
//! ([`faceanim_rig::name_map`]): any spelling of a channel (`jawOpen`, `JawOpen`, `eyeBlink_L`,
//! `Eye_Blink_L`), the mean of a split channel's halves (ICT's `browInnerUp_L`/`_R`), a merged
//! shape for both its channels (`mouthSmile`); ARKit shapes the clip lacks are written as 0. The eyes' angles
//! are derived from the eyeLook weights (at weight 1: 30° sideways, 25° up or down), since a
//! clip carries no eye bones.

use faceanim_rig::name_map::NameMap;
use faceanim_rig::names::ARKIT_52;

use faceanim_anim::Clip;

const ROTATIONS: [&str; 9] = [
    "HeadYaw",
    "HeadPitch",
    "HeadRoll",
    "LeftEyeYaw",
    "LeftEyePitch",
    "LeftEyeRoll",
    "RightEyeYaw",
    "RightEyePitch",
    "RightEyeRoll",
];

const EYE_SIDEWAYS_DEGREES: f32 = 30.0;
const EYE_VERTICAL_DEGREES: f32 = 25.0;

/// `HH:MM:SS:FF.mmm` for frame `index` at `fps`: frames counted at the rounded rate, and the
/// fraction of a frame in thousandths (0 for integer rates).
fn timecode(index: usize, fps: f32) -> String {
    let seconds = index as f64 / f64::from(fps);
    let whole = seconds.floor();
    let rate = f64::from(fps).round().max(1.0);
    let frame = (seconds - whole) * rate;
    let total = whole as u64;
    format!(
        "{:02}:{:02}:{:02}:{:02}.{:03}",
        total / 3600,
        (total / 60) % 60,
        total % 60,
        frame.floor() as u64,
        ((frame - frame.floor()) * 1000.0).round().min(999.0) as u64
    )
}

fn capitalise(name: &str) -> String {
    let mut chars = name.chars();
    chars
        .next()
        .map(|c| c.to_ascii_uppercase().to_string() + chars.as_str())
        .unwrap_or_default()
}

/// The clip as a Live Link Face CSV (see the module docs).
#[must_use]
pub fn to_csv(clip: &Clip) -> String {
    let map = NameMap::from_names(&clip.blendshapes, &[]);
    let mut out = String::from("Timecode,BlendShapeCount");
    for name in ARKIT_52 {
        out.push(',');
        out.push_str(&capitalise(name));
    }
    for name in ROTATIONS {
        out.push(',');
        out.push_str(name);
    }
    out.push('\n');
    let index_of = |arkit: &str| ARKIT_52.iter().position(|n| *n == arkit);
    for (f, row) in clip.frames.iter().enumerate() {
        let values: Vec<f32> = map
            .channel_values(row)
            .into_iter()
            .map(|v| v.unwrap_or(0.0))
            .collect();
        let get = |arkit: &str| index_of(arkit).map_or(0.0, |i| values[i]);
        let head = clip
            .head
            .as_ref()
            .and_then(|h| h.get(f))
            .copied()
            .unwrap_or([0.0; 3]);
        // Positive yaw turns towards the subject's own left (as the head's yaw does): the left
        // eye looking out, or the right eye looking in.
        let left_yaw = (get("eyeLookOutLeft") - get("eyeLookInLeft")) * EYE_SIDEWAYS_DEGREES;
        let right_yaw = (get("eyeLookInRight") - get("eyeLookOutRight")) * EYE_SIDEWAYS_DEGREES;
        let left_pitch = (get("eyeLookUpLeft") - get("eyeLookDownLeft")) * EYE_VERTICAL_DEGREES;
        let right_pitch = (get("eyeLookUpRight") - get("eyeLookDownRight")) * EYE_VERTICAL_DEGREES;
        out.push_str(&timecode(f, clip.fps));
        out.push_str(&format!(",{}", ARKIT_52.len() + ROTATIONS.len()));
        for v in values {
            out.push_str(&format!(",{v:.6}"));
        }
        for degrees in [
            head[0],
            head[1],
            head[2],
            left_yaw,
            left_pitch,
            0.0,
            right_yaw,
            right_pitch,
            0.0,
        ] {
            out.push_str(&format!(",{:.6}", degrees.to_radians()));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_order_timecode_and_values() {
        let clip = Clip {
            fps: 30.0,
            blendshapes: vec!["jawOpen".into(), "eyeBlink_L".into(), "custom".into()],
            frames: vec![vec![0.5, 1.0, 0.3]; 32],
            head: Some(vec![[90.0, 0.0, -45.0]; 32]),
            head_position: None,
            presence: None,
        };
        let csv = to_csv(&clip);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 33);
        let header: Vec<&str> = lines[0].split(',').collect();
        assert_eq!(header.len(), 63);
        assert_eq!(
            &header[..4],
            [
                "Timecode",
                "BlendShapeCount",
                "EyeBlinkLeft",
                "EyeLookDownLeft"
            ]
        );
        assert_eq!(
            &header[16..20],
            ["JawForward", "JawLeft", "JawRight", "JawOpen"]
        );
        assert_eq!(&header[53..56], ["TongueOut", "HeadYaw", "HeadPitch"]);
        assert_eq!(header[62], "RightEyeRoll");
        let row: Vec<&str> = lines[32].split(',').collect();
        assert_eq!(row[0], "00:00:01:01.000");
        assert_eq!(row[1], "61");
        assert_eq!(row[2], "1.000000");
        assert_eq!(row[19], "0.500000");
        assert_eq!(row[54], format!("{:.6}", std::f32::consts::FRAC_PI_2));
        assert_eq!(row[56], format!("{:.6}", -std::f32::consts::FRAC_PI_4));
    }

    #[test]
    fn fractional_rates_keep_subframes() {
        assert_eq!(timecode(0, 29.97), "00:00:00:00.000");
        assert_eq!(timecode(3600 * 30, 30.0), "01:00:00:00.000");
        assert_eq!(timecode(1, 60.0), "00:00:00:01.000");
    }
}
