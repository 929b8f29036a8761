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
//!
//! [`from_csv`] reads such a file back (the app's recordings and ours) as a clip of ARKit
//! names with the head's angles: the rate from the timecodes' frame numbers, a frame the
//! recording skipped held from the one before.

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
/// fraction of a frame in thousandths (0 for integer rates). Counted in whole thousandths of a
/// frame, so that a time a rounding error short of a frame is that frame (frame 335 at 240 fps
/// is `00:00:01:95.000`, not `94.999`).
fn timecode(index: usize, fps: f32) -> String {
    let seconds = index as f64 / f64::from(fps);
    let rate = f64::from(fps).round().max(1.0) as u64;
    let thousandths = (seconds * rate as f64 * 1000.0).round() as u64;
    let frames = thousandths / 1000;
    let total = frames / rate;
    format!(
        "{:02}:{:02}:{:02}:{:02}.{:03}",
        total / 3600,
        (total / 60) % 60,
        total % 60,
        frames % rate,
        thousandths % 1000
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
        let values = map.arkit_row(row);
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

/// The frame rates a Live Link Face timecode counts in, slowest first (240: what faceanim's
/// lip sync writes at its fastest).
const RATES: [f32; 8] = [24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 120.0, 240.0];
/// The longest recording read: one hour at 120 fps.
const MAX_FRAMES: usize = 3600 * 120;

/// Why a Live Link Face CSV could not be read: the line (1 is the header) and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {problem}")]
pub struct CsvError {
    /// The line, counting the header as 1.
    pub line: usize,
    /// What is wrong there.
    pub problem: String,
}

/// A timecode: whole seconds, the frame within the second, and the fraction of a frame.
type Timecode = (u64, u32, f32);

/// One row of a recording: its timecode, its curves' weights, the head's yaw, pitch, roll.
type Row = (Timecode, Vec<f32>, [f32; 3]);

/// `HH:MM:SS:FF` or `HH:MM:SS:FF.mmm` as a [`Timecode`].
fn parse_timecode(text: &str) -> Option<Timecode> {
    let mut parts = text.trim().split(':');
    let mut next = || parts.next()?.parse::<u64>().ok();
    let (h, m, s) = (next()?, next()?, next()?);
    let last = parts.next()?;
    if parts.next().is_some() || m >= 60 || s >= 60 {
        return None;
    }
    let (frame, fraction) = match last.split_once('.') {
        Some((f, sub)) => (f.parse().ok()?, format!("0.{sub}").parse().ok()?),
        None => (last.parse().ok()?, 0.0),
    };
    Some((h * 3600 + m * 60 + s, frame, fraction))
}

/// Reads a Live Link Face CSV (see the module docs): the 52 ARKit curves it has by their
/// ARKit names, the head's yaw, pitch and roll (radians in the file) in degrees.
///
/// # Errors
/// A [`CsvError`] naming the line and the column or value.
pub fn from_csv(text: &str) -> Result<Clip, CsvError> {
    let at = |line: usize, problem: String| CsvError { line, problem };
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(at(1, "the file is empty".into()));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    if !columns[0].eq_ignore_ascii_case("timecode") {
        return Err(at(
            1,
            format!(
                "the first column is '{}', not Timecode: not a Live Link Face CSV",
                faceanim_rig::excerpt(columns[0])
            ),
        ));
    }
    let channel_of = |name: &str| ARKIT_52.iter().position(|a| a.eq_ignore_ascii_case(name));
    let channels: Vec<(usize, usize)> = columns
        .iter()
        .enumerate()
        .filter_map(|(c, name)| channel_of(name).map(|k| (c, k)))
        .collect();
    if channels.is_empty() {
        return Err(at(
            1,
            "no column is an ARKit blendshape (EyeBlinkLeft, JawOpen, …)".into(),
        ));
    }
    let head_columns: Option<Vec<usize>> = ROTATIONS[..3]
        .iter()
        .map(|r| columns.iter().position(|c| c.eq_ignore_ascii_case(r)))
        .collect();
    let mut rows: Vec<Row> = Vec::new();
    for (index, line) in lines {
        let number = index + 1;
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != columns.len() {
            return Err(at(
                number,
                format!("{} values for {} columns", fields.len(), columns.len()),
            ));
        }
        let time = parse_timecode(fields[0]).ok_or_else(|| {
            at(
                number,
                format!(
                    "Timecode '{}' is not HH:MM:SS:FF.mmm",
                    faceanim_rig::excerpt(fields[0])
                ),
            )
        })?;
        let value = |c: usize| -> Result<f32, CsvError> {
            fields[c]
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    at(
                        number,
                        format!(
                            "{}: '{}' is not a number",
                            columns[c],
                            faceanim_rig::excerpt(fields[c])
                        ),
                    )
                })
        };
        let mut weights = vec![0.0f32; channels.len()];
        for (w, &(c, _)) in weights.iter_mut().zip(&channels) {
            *w = value(c)?;
        }
        let mut head = [0.0f32; 3];
        if let Some(hc) = &head_columns {
            for (h, &c) in head.iter_mut().zip(hc) {
                *h = value(c)?.to_degrees();
            }
        }
        rows.push((time, weights, head));
        if rows.len() > MAX_FRAMES {
            return Err(at(number, format!("more than {MAX_FRAMES} frames")));
        }
    }
    let Some(first) = rows.first().map(|r| r.0) else {
        return Err(at(2, "the recording has no frames".into()));
    };
    // The rate: the slowest the timecodes' frame numbers fit in (a recording under a second
    // long shows too few of them to tell: Live Link Face records at 60).
    let highest = rows.iter().map(|r| r.0.1).max().unwrap_or(0) as f32;
    let spans_a_second = rows.iter().any(|r| r.0.0 != first.0);
    let rate = RATES
        .into_iter()
        .find(|&r| r > highest && (spans_a_second || r >= 60.0))
        .ok_or_else(|| {
            at(
                2,
                format!("frame number {highest} in a timecode: faster than 240 fps"),
            )
        })?;
    let count_of =
        |(s, f, sub): (u64, u32, f32)| s as f64 * f64::from(rate) + f64::from(f) + f64::from(sub);
    let start = count_of(first);
    let mut frames: Vec<Vec<f32>> = Vec::new();
    let mut heads: Vec<[f32; 3]> = Vec::new();
    for (k, (time, weights, head)) in rows.into_iter().enumerate() {
        let index = (count_of(time) - start).round();
        if index < frames.len() as f64 - 1.0 || index >= MAX_FRAMES as f64 {
            return Err(at(
                k + 2,
                "the timecode goes back before the row above it".into(),
            ));
        }
        let index = index as usize;
        // Frames the recording skipped hold the one before.
        while frames.len() < index {
            frames.push(frames.last().cloned().unwrap_or_else(|| weights.clone()));
            heads.push(heads.last().copied().unwrap_or(head));
        }
        frames.truncate(index);
        heads.truncate(index);
        frames.push(weights);
        heads.push(head);
    }
    Ok(Clip {
        fps: rate,
        blendshapes: channels
            .iter()
            .map(|&(_, k)| ARKIT_52[k].to_owned())
            .collect(),
        frames,
        head: head_columns.map(|_| heads),
        head_position: None,
        presence: None,
        arkit: None,
    })
}

#[cfg(test)]
#[allow(clippy::float_cmp, reason = "rates and copied values are exact")]
mod tests {
    use super::*;

    #[test]
    fn what_is_written_reads_back() {
        let frames: Vec<Vec<f32>> = (0..75)
            .map(|f| vec![f as f32 / 74.0, 1.0 - f as f32 / 74.0])
            .collect();
        let clip = Clip {
            fps: 30.0,
            blendshapes: vec!["jawOpen".into(), "eyeBlinkLeft".into()],
            frames: frames.clone(),
            head: Some((0..75).map(|f| [f as f32 * 0.2, -3.0, 1.5]).collect()),
            head_position: None,
            presence: None,
            arkit: None,
        };
        let back = from_csv(&to_csv(&clip)).unwrap();
        assert_eq!(back.fps, 30.0);
        assert_eq!(back.frames.len(), 75);
        assert_eq!(back.blendshapes.len(), 52);
        let jaw = back.column("jawOpen").unwrap();
        let blink = back.column("eyeBlinkLeft").unwrap();
        for (f, row) in frames.iter().enumerate() {
            assert!((back.frames[f][jaw] - row[0]).abs() < 1e-5);
            assert!((back.frames[f][blink] - row[1]).abs() < 1e-5);
            let head = back.head.as_ref().unwrap()[f];
            assert!((head[0] - f as f32 * 0.2).abs() < 1e-3 && (head[1] + 3.0).abs() < 1e-3);
        }
        // Lip sync's fastest rate and NTSC's, over more than a second (a shorter recording
        // shows too few frame numbers to tell its rate): as long, to a frame, at the rate its
        // timecodes count in (NTSC's 30).
        for (fps, counted) in [(240.0, 240.0), (30_000.0 / 1001.0, 30.0)] {
            let fast = Clip {
                fps,
                frames: vec![vec![0.5, 0.25]; 900],
                head: None,
                ..clip.clone()
            };
            let back = from_csv(&to_csv(&fast)).unwrap();
            assert_eq!(back.fps, counted);
            let seconds = |c: &Clip| (c.frames.len() - 1) as f32 / c.fps;
            assert!(
                (seconds(&back) - seconds(&fast)).abs() <= 1.0 / counted,
                "{fps}: {} s read back from {} s",
                seconds(&back),
                seconds(&fast)
            );
        }
    }

    #[test]
    fn a_recording_from_the_middle_of_the_day_with_a_skipped_frame() {
        let header = "Timecode,BlendShapeCount,JawOpen,MouthClose,HeadYaw,HeadPitch,HeadRoll";
        let text = format!(
            "{header}\n16:33:39:58.500,5,0.1,0,0,0,0\n16:33:39:59.500,5,0.2,0,0,0,0\n16:33:40:01.500,5,0.4,0,0,0,0\n"
        );
        let clip = from_csv(&text).unwrap();
        assert_eq!(clip.fps, 60.0);
        let jaw: Vec<f32> = clip.frames.iter().map(|r| r[0]).collect();
        assert_eq!(jaw, [0.1, 0.2, 0.2, 0.4]);
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let header = "Timecode,BlendShapeCount,JawOpen";
        assert_eq!(from_csv("").unwrap_err().line, 1);
        assert!(
            from_csv("name,value\n")
                .unwrap_err()
                .problem
                .contains("not a Live Link Face CSV")
        );
        assert!(
            from_csv("Timecode,Foo\n")
                .unwrap_err()
                .problem
                .contains("ARKit")
        );
        let e = from_csv(&format!("{header}\n00:00:00:00.000,1,x\n")).unwrap_err();
        assert_eq!(
            (e.line, e.problem.as_str()),
            (2, "JawOpen: 'x' is not a number")
        );
        let e = from_csv(&format!("{header}\n00:00:00:00.000,1\n")).unwrap_err();
        assert!(e.problem.contains("2 values for 3 columns"));
        let e = from_csv(&format!("{header}\n0:0:0\n")).unwrap_err();
        assert!(e.problem.contains("values") || e.problem.contains("Timecode"));
        let e = from_csv(&format!(
            "{header}\n00:00:01:00.000,1,0\n00:00:00:00.000,1,0\n"
        ))
        .unwrap_err();
        assert_eq!(e.line, 3);
    }

    #[test]
    fn header_order_timecode_and_values() {
        let clip = Clip {
            fps: 30.0,
            blendshapes: vec!["jawOpen".into(), "eyeBlink_L".into(), "custom".into()],
            frames: vec![vec![0.5, 1.0, 0.3]; 32],
            head: Some(vec![[90.0, 0.0, -45.0]; 32]),
            head_position: None,
            presence: None,
            arkit: None,
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
        assert_eq!(timecode(335, 240.0), "00:00:01:95.000");
        assert_eq!(timecode(59, 60.0), "00:00:00:59.000");
        assert_eq!(timecode(30, 30_000.0 / 1001.0), "00:00:01:00.030");
        assert_eq!(timecode(1, 29.97), "00:00:00:01.001");
    }
}
