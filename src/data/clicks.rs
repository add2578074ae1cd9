//! The clicks file of `label --clicks`: a JSON list of {"object", "x", "y", "angle"}, one click
//! per labelling round, grouped per object in order (docs/data.md).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context as _};

use super::labels::Label;
use crate::grasp::{PixelError, PixelGrasp};

/// Parses a clicks file: a JSON list of {"object", "x", "y", "angle"}, grouped per object in order.
pub(crate) fn read_clicks(
    path: &Path,
    train: &[String],
    test: &[String],
) -> anyhow::Result<BTreeMap<String, Vec<Label>>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading --clicks {}", path.display()))?;
    parse_clicks(&text, path, train, test)
}

/// Parses a clicks file's text; `path` names it in errors. Clicks label the `train` objects;
/// one for a `test` object is refused as such.
pub(crate) fn parse_clicks(
    text: &str,
    path: &Path,
    train: &[String],
    test: &[String],
) -> anyhow::Result<BTreeMap<String, Vec<Label>>> {
    let value: serde_json::Value = serde_json::from_str(text)
        .with_context(|| format!("--clicks {} is not valid JSON", path.display()))?;
    let list = value.as_array().with_context(|| {
        format!(
            "--clicks {}: expected a list of {{\"object\", \"x\", \"y\", \"angle\"}}",
            path.display()
        )
    })?;
    let mut clicks: BTreeMap<String, Vec<Label>> = BTreeMap::new();
    for (i, entry) in list.iter().enumerate() {
        let at = || format!("--clicks {} entry {}", path.display(), i + 1);
        let object = entry
            .get("object")
            .and_then(|o| o.as_str())
            .with_context(|| format!("{}: missing \"object\" name", at()))?;
        if test.iter().any(|t| t == object) {
            bail!(
                "{}: '{object}' is a test object, held out of labelling; clicks label the training objects ({})",
                at(),
                train.join(", ")
            );
        }
        if !train.iter().any(|t| t == object) {
            bail!(
                "{}: unknown object '{object}' (training objects: {})",
                at(),
                train.join(", ")
            );
        }
        let number = |key: &str| {
            entry
                .get(key)
                .and_then(|v| v.as_f64())
                .filter(|v| v.is_finite())
                .with_context(|| {
                    format!(
                        "{}: \"{key}\" = {} is not a number",
                        at(),
                        entry.get(key).map_or("missing".into(), |v| v.to_string())
                    )
                })
        };
        let grasp = match PixelGrasp::checked(number("x")?, number("y")?, number("angle")?) {
            Ok(grasp) => grasp,
            Err(PixelError::OutOfImage { axis, value, max }) => {
                bail!(
                    "{}: \"{axis}\" = {value} must be an integer in 0..={max}",
                    at()
                )
            }
            Err(other) => bail!("{}: {other}", at()),
        };
        let label = Label::from(grasp);
        clicks.entry(object.to_owned()).or_default().push(label);
    }
    Ok(clicks)
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;

    use crate::data::fuzzing::{check, config, edits, mutate, text};

    const CLICKS: &str = r#"[{"object": "YcbHammer", "x": 64, "y": 70, "angle": 45},
     {"object": "YcbTomatoSoupCan", "x": 12, "y": 100, "angle": 112.5}]"#;

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_json_clicks(edits in edits()) {
            let input = text(&mutate(CLICKS.as_bytes(), &edits));
            let train = ["YcbHammer".to_owned(), "YcbTomatoSoupCan".to_owned()];
            check(|| crate::data::clicks::parse_clicks(&input, Path::new("clicks.json"), &train, &[]))?;
        }
    }
}
