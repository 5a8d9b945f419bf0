//! `alignment-studies taps`: fits the estimator FMU's learned filter (the tap bank,
//! resources/learned.taps) in the metric's bands.

use super::{CALIBRATION_SEED, Report, StandardFmus};
use crate::Error;
use crate::study::learned::taps::Options;
use fmu_estimator::learned::bank::Encoding;

/// `--encoding`: `i12`, `i16` or `f32`.
fn encoding(s: &str) -> Result<Encoding, String> {
    match s {
        "i12" => Ok(Encoding::I12),
        "i16" => Ok(Encoding::I16),
        "f32" => Ok(Encoding::F32),
        _ => Err(format!("expected i12, i16 or f32, got '{s}'")),
    }
}
use clap::Args;
use std::path::PathBuf;

/// `taps`' options.
#[derive(Args, Clone, Debug)]
pub struct TapsArgs {
    /// The vehicle and estimator FMUs.
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// Speeds of the bank in m/s.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "5,7.5,10,12.5,15,17.5,20,22.5,25,27.5,30",
        allow_negative_numbers = true,
        value_parser = super::speed
    )]
    pub speeds: Vec<f64>,
    /// Kalker-coefficient scales of the training runs (one run each): each condition gets its
    /// own taps, blended at run time by the contact model fitted with them.
    #[arg(long, value_delimiter = ',', default_value = "1,0.75,0.5", allow_negative_numbers = true, value_parser = super::kalker_scale)]
    pub kalker_scales: Vec<f64>,
    /// The wheels' equivalent conicities of the training runs, each with every Kalker scale:
    /// each pair gets its own taps, blended at run time by the estimated (or given) conicity.
    /// 0: the vehicle's own, no conicity conditions (as learned-nominal.taps).
    #[arg(long, value_delimiter = ',', default_value = "0.05,0.075,0.1,0.15,0.2,0.3,0.4", value_parser = super::conicity)]
    pub conicities: Vec<f64>,
    /// The conicities (of --conicities) at which the four-sensor taps are fitted.
    #[arg(long, value_delimiter = ',', default_value = "0.1", value_parser = super::conicity)]
    pub roll_rate_conicities: Vec<f64>,
    /// One set of taps fitted on every condition's runs at once, no contact model.
    #[arg(long)]
    pub pooled: bool,
    /// Lags of the fixed-lag entries in m.
    #[arg(long, value_delimiter = ',', default_value = "10", allow_negative_numbers = true, value_parser = super::lag)]
    pub lags: Vec<f64>,
    /// Fit only the three-sensor taps (the vehicle has no ws_roll_rate).
    #[arg(long)]
    pub no_roll_rate: bool,
    /// How the bank stores its taps: i12 (per channel a scale and 12-bit multiples of it, 0.4
    /// times the size of f32; as precise as the estimates need), i16 (16-bit multiples) or f32.
    #[arg(long, default_value = "i12", value_parser = encoding)]
    pub encoding: Encoding,
    /// Keep this tap bank's taps and refit only its contact model and model spectra (same runs,
    /// no tap solves).
    #[arg(long, value_name = "BANK")]
    pub taps_from: Option<PathBuf>,
    /// With --taps-from and one --conicities (the one those taps were fitted at): take this
    /// bank's contact model (fitted over conicities) instead of fitting one; no runs, so the
    /// fit's other options (speeds, scales, lags, encoding, seeds) are not used. The default
    /// bank is made so: its taps know when the wheels are not the ones they were fitted for
    /// (`outside_training`).
    #[arg(long, value_name = "BANK")]
    pub contact_from: Option<PathBuf>,
    /// Spread every condition's runs over the vehicle and this many random variants of it
    /// (masses, inertias, wheelbase, bogie spacing, suspension stiffness and damping within
    /// about +-40 %, wheel radius +-15 %; `studies/src/study/vehicles.rs`): taps that hold for
    /// a family of vehicles, not one. 0: the vehicle alone.
    #[arg(long, default_value_t = 0)]
    pub vehicle_family: usize,
    /// The seed that draws the --vehicle-family variants.
    #[arg(long, default_value_t = 1)]
    pub family_seed: u64,
    /// Track seed of the training runs.
    #[arg(long, default_value_t = CALIBRATION_SEED)]
    pub seed: u32,
    /// Track seeds the ridge and band weights are chosen on (neither the training seed nor an
    /// evaluation seed).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "102,103,104,105,106,107,108,109,110,111,112,113,114,115,116,117,118,119,120,121"
    )]
    pub validation_seeds: Vec<u32>,
    /// Those of --validation-seeds the contact model is judged on (its errors, young memories
    /// and novelty level): the fallback's nodes were chosen for the level these give.
    #[arg(long, value_delimiter = ',', default_value = "102,103,104,105,106")]
    pub contact_validation_seeds: Vec<u32>,
    /// The file to write (a tap bank written before, such as the shipped one, is replaced).
    #[arg(long, default_value = "fmu-estimator/resources/learned-conicity.taps")]
    pub out: PathBuf,
    /// Replace an existing file at --out that this command did not write (never an input, a
    /// symlink, a FIFO or a directory).
    #[arg(long)]
    pub force: bool,
}

/// How every tap bank begins (`fmu-estimator/src/learned/bank.rs`).
const MARK: &[u8] = b"learned-taps ";

/// The fit's options from the command line (the command line goes into the bank's provenance
/// when they are not the shipped bank's), then the fit ([`crate::report::learned::taps`]).
pub fn execute(a: &TapsArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    let mut inputs = vec![a.fmus.vehicle.as_path(), a.fmus.estimator.as_path()];
    inputs.extend(a.taps_from.as_deref());
    inputs.extend(a.contact_from.as_deref());
    let guard = super::guard(&a.out, &inputs, a.force, Some(MARK))?;
    let mut o = Options::shipped();
    o.speeds = a.speeds.clone();
    o.kalker_scales = a.kalker_scales.clone();
    o.per_condition = !a.pooled;
    o.conicities = super::own_conicities(&a.conicities)?;
    o.roll_rate_conicities = if o.conicities.is_empty() {
        vec![]
    } else {
        super::own_conicities(&a.roll_rate_conicities)?
    };
    o.lags = a.lags.clone();
    o.roll_rate = !a.no_roll_rate;
    o.training_seed = a.seed;
    o.encoding = a.encoding;
    if let Some(p) = &a.taps_from {
        o.taps_from = Some(
            fmu_estimator::learned::bank::Bank::load(p).map_err(|e| Error::input(e.to_string()))?,
        );
    }
    if let Some(p) = &a.contact_from {
        o.contact_from = Some(
            fmu_estimator::learned::bank::Bank::load(p)
                .map_err(|e| Error::input(format!("--contact-from: {e}")))?,
        );
    }
    o.validation_seeds = a.validation_seeds.clone();
    o.contact_validation_seeds = a.contact_validation_seeds.clone();
    crate::study::learned::taps::check(&o)?;
    let defaults = Options::shipped();
    if a.taps_from.is_some()
        || (
            o.conicities.clone(),
            o.roll_rate_conicities.clone(),
            o.encoding,
        ) != (
            defaults.conicities.clone(),
            defaults.roll_rate_conicities.clone(),
            defaults.encoding,
        )
        || (
            o.speeds.clone(),
            o.kalker_scales.clone(),
            o.per_condition,
            o.lags.clone(),
            o.roll_rate,
            o.training_seed,
            o.validation_seeds.clone(),
            o.contact_validation_seeds.clone(),
        ) != (
            defaults.speeds,
            defaults.kalker_scales,
            defaults.per_condition,
            defaults.lags,
            defaults.roll_rate,
            defaults.training_seed,
            defaults.validation_seeds,
            defaults.contact_validation_seeds,
        )
    {
        o.command = std::env::args().collect::<Vec<_>>().join(" ");
    }
    // The family's vehicle files live until the fit ends.
    let family_dir = tempfile::tempdir()
        .map_err(|e| Error::Io(format!("a temporary directory for the family: {e}")))?;
    if a.vehicle_family > 0 {
        let base = a.fmus.fmus().vehicle_params()?;
        let mut members = vec![base.clone()];
        members.extend(crate::study::vehicles::family(
            &base,
            a.family_seed,
            a.vehicle_family,
        ));
        o.vehicles = crate::study::vehicles::write(&members, family_dir.path(), "vehicle")?;
        o.command = std::env::args().collect::<Vec<_>>().join(" ");
    }
    let mut report = crate::report::learned::taps(&a.fmus.fmus(), &o, &a.out, log)?;
    report.guarded.push(guard);
    Ok(report)
}
