//! Parsing one flag's value: names of options, seed lists, pixels, label addresses and numbers
//! in their documented ranges, each refusing a bad value with a message that names it.

use crate::model::autotune::{self, Workload};
use crate::model::unet::Precision;
use anyhow::{bail, Context as _};
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};

use crate::grasp::PixelGrasp;
use crate::named::Named;

/// A value parser for a [`Named`] enum: its names, with their help, and nothing else.
pub(super) fn named<T: Named>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(
        T::ALL
            .iter()
            .map(|v| PossibleValue::new(v.name()).help(v.help())),
    )
    .map(|name| {
        T::ALL
            .iter()
            .copied()
            .find(|v| v.name() == name)
            .unwrap_or(T::ALL[0])
    })
}

/// Seeds given as a list and/or ranges.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SeedList(pub(crate) Vec<u64>);

/// Parses `1-10`, `0,1000,2000` or a mix such as `1-3,7`.
pub(crate) fn parse_seed_list(text: &str) -> Result<SeedList, String> {
    let fail =
        |why: &str| format!("'{text}' {why}; use a list and/or ranges such as 1-10 or 0,1000,2000");
    let mut seeds = Vec::new();
    for part in text.split(',').map(str::trim) {
        let number = |s: &str| {
            s.trim()
                .parse::<u64>()
                .map_err(|_| fail(&format!("has '{s}', not a seed")))
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (number(a)?, number(b)?);
                if a > b {
                    return Err(fail(&format!("has the empty range {a}-{b}")));
                }
                if b - a >= 100_000 {
                    return Err(fail("spans more than 100000 seeds"));
                }
                seeds.extend(a..=b);
            }
            None => seeds.push(number(part)?),
        }
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(d) = seeds.iter().find(|s| !seen.insert(**s)) {
        return Err(fail(&format!("repeats seed {d}")));
    }
    Ok(SeedList(seeds))
}

/// `YcbHammer:3`: an object and a label number from 1.
pub(super) fn parse_label_address(text: &str) -> Result<(String, usize), String> {
    let fail = || format!("'{text}' is not OBJECT:K, e.g. YcbHammer:3 (K counts from 1)");
    let (object, k) = text.rsplit_once(':').ok_or_else(fail)?;
    let k = k
        .parse::<usize>()
        .ok()
        .filter(|&k| k >= 1)
        .ok_or_else(fail)?;
    if object.is_empty() {
        return Err(fail());
    }
    Ok((object.to_owned(), k))
}

pub(super) fn fraction(text: &str) -> Result<f32, String> {
    non_negative(text)
        .ok()
        .filter(|&v| v <= 1.0)
        .ok_or_else(|| format!("'{text}' must be a fraction from 0 to 1"))
}

/// A value parser for a finite number in (0, `max`]: the flags whose range the help gives.
pub(super) fn positive_up_to<T>(
    max: f64,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: std::str::FromStr + Into<f64> + Copy + Send + Sync + 'static,
{
    move |text: &str| match text.parse::<T>() {
        Ok(v) if v.into() > 0.0 && v.into() <= max => Ok(v),
        _ => Err(format!(
            "'{text}' must be a number above 0 and at most {max}"
        )),
    }
}

/// A value parser for a finite number in [0, `max`].
pub(super) fn non_negative_up_to(
    max: f32,
) -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync {
    move |text: &str| match non_negative(text) {
        Ok(v) if v <= max => Ok(v),
        _ => Err(format!("'{text}' must be a number from 0 to {max}")),
    }
}

pub(super) fn non_negative(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v >= 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("'{text}' must be a non-negative number")),
    }
}

/// Parses a `U,V` pixel and checks that it lies in the 128 × 128 image.
pub(crate) fn parse_pixel(text: &str) -> anyhow::Result<(u32, u32)> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let [u, v] = parts.as_slice() else {
        bail!("--pixel '{text}' must be two integers U,V, e.g. --pixel 64,70");
    };
    let parse = |s: &str| {
        s.parse::<u32>()
            .with_context(|| format!("--pixel '{text}': '{s}' is not a non-negative integer"))
    };
    let (u, v) = (parse(u)?, parse(v)?);
    let grasp = PixelGrasp::checked(f64::from(u), f64::from(v), 0.0).with_context(|| {
        format!("--pixel {u},{v} is outside the 128 × 128 image (use 0..=127 for each)")
    })?;
    Ok((grasp.u, grasp.v))
}

/// `--precision` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum PrecisionChoice {
    /// The faster on this machine, as timed once per CPU and ISA cap and kept in
    /// ~/.cache/graspmap/precision.json (`graspmap bench precision` shows the figures).
    Auto,
    /// float32 throughout.
    Fp32,
    /// bf16 convolutions (channels_last) over float32 master weights.
    Bf16,
}

impl PrecisionChoice {
    /// The precision to use on this machine for `workload`.
    pub(crate) fn resolve(self, workload: Workload) -> Precision {
        match self {
            PrecisionChoice::Auto => autotune::auto(workload),
            PrecisionChoice::Fp32 => Precision::Fp32,
            PrecisionChoice::Bf16 => Precision::Bf16,
        }
    }

    /// As [`Self::resolve`] where the run uses the network; where it does not (the oracle and
    /// random policies), auto is fp32 without timing anything.
    pub(crate) fn resolve_for(self, workload: Workload, uses_network: bool) -> Precision {
        match (self, uses_network) {
            (PrecisionChoice::Auto, false) => Precision::Fp32,
            _ => self.resolve(workload),
        }
    }
}
