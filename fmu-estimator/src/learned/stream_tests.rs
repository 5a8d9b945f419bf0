//! Tests of the streaming learned filter (`stream.rs` and the parts it runs: history,
//! selection, blend, extrapolation, delay line), through `Learned`.

use super::super::bank::Entry;
use super::super::bank::tests::sample_bank;
use super::super::grid::CHANNELS;
use super::*;

/// The estimate straight from the taps (file order), for the oracle: channel values of the
/// cells pushed so far, newest last. Deliberately not `window::Window`: it is the bank format's
/// definition in plain sums, so it checks the shared code's tap order and partial sums, which
/// the fit uses too.
fn direct(entry: &Entry, window: usize, cells: &[[f64; 5]]) -> f64 {
    let w = &entry.windows[window];
    let len = w.past + w.future + 1;
    let mut e = 0.0;
    for (c, name) in entry.channels.iter().enumerate() {
        let slot = CHANNELS.iter().position(|n| n == name).unwrap();
        for j in 0..len {
            e += w.taps[c * len + j] * cells[cells.len() - 1 - j][slot];
        }
    }
    e
}

/// The learned filter with the three-sensor taps of `bank` and the fixed lag `lag` \[m\].
fn three_sensors(bank: &Bank, lag: f64) -> Learned {
    Learned::new(
        bank,
        Choice {
            roll_rate: false,
            lag,
            conicity: None,
            kalker: None,
        },
    )
    .unwrap()
}

/// Sample `k` of a test record: a sine in the first channel, a cosine in the Kalman channel.
fn sample(k: usize) -> [f64; 5] {
    [
        (k as f64 * 0.3).sin(),
        0.0,
        0.0,
        0.0,
        (k as f64 * 0.11).cos(),
    ]
}

#[test]
fn grid_estimates_are_the_taps_applied_to_the_history_blended_in_speed() {
    let bank = sample_bank();
    let mut l = three_sensors(&bank, 0.6);
    assert!((l.lag() - 0.6).abs() < 1e-12);
    // 0.05 m per sample at 12.5 m/s, 4 samples per 0.2 m cell.
    let mut grid = Grid::new(0.2, 500.0, None);
    let mut cells = vec![];
    let mut d = 0.0;
    for k in 0..200 {
        d += 0.05;
        let x = sample(k);
        if let Some(c) = grid.add(d, &x) {
            cells.extend(c.cells);
        }
        l.step(d, 12.5, &x, 0.0);
    }
    let a = 0.25; // 12.5 m/s between 10 and 20
    // Enough history for the longest window (5 behind, 3 ahead).
    let e10 = &bank.entries[0];
    let e20 = &bank.entries[1];
    let want = (1.0 - a) * direct(e10, 1, &cells) + a * direct(e20, 1, &cells);
    let (got, _) = l.causal(l.causal.points[1].distance).unwrap();
    assert!(
        (got - want).abs() < 1e-12 * want.abs().max(1.0),
        "{got} {want}"
    );
    let want =
        (1.0 - a) * direct(&bank.entries[2], 1, &cells) + a * direct(&bank.entries[3], 1, &cells);
    let (got, _) = l.lagged(l.lagged.points[1].distance).unwrap();
    assert!(
        (got - want).abs() < 1e-12 * want.abs().max(1.0),
        "{got} {want}"
    );
}

#[test]
fn per_condition_taps_are_blended_by_the_estimated_or_told_contact() {
    use crate::learned::contact::{ContactModel, SpeedModel};
    let mut bank = sample_bank();
    // Two conditions at each speed: the sample taps (0.5) and their negatives (1.0).
    bank.entries.retain(|e| e.lag == 0);
    let mut more = bank.entries.clone();
    for e in &mut bank.entries {
        e.condition = Some(0.5);
    }
    for e in &mut more {
        e.condition = Some(1.0);
        for w in &mut e.windows {
            w.taps.iter_mut().for_each(|t| *t = -*t);
        }
    }
    bank.entries.extend(more);
    // The scale follows the first feature: 0.75 + 0.1 ln(M_11 / M_00).
    bank.contact = Some(ContactModel {
        band: [3.0, 25.0],
        extra_bands: vec![],
        memory: 10.0,
        range: [0.5, 1.0],
        speeds: vec![SpeedModel {
            speed: 10.0,
            coefficients: vec![0.1, 0.0, 0.0, 0.0, 0.0, 0.75],
            rms_error: 0.1,
            conicity: None,
            kalker_by_conicity: vec![],
            spectra: None,
        }],
        conicity_range: None,
    });
    // Written and read back (the contact model's absent conicity parts included).
    let back = Bank::parse(&bank.to_bytes(), std::path::Path::new("k.taps")).unwrap();
    assert_eq!(back.contact, bank.contact);
    // Channel 1 is 0.12 x channel 0: at 10 m/s, over the speed and its square
    // (contact::CONTACT_SPEED_POWER), 1.2 times: ln(1.44) = 0.365, scale 0.786.
    let signal: Vec<(f64, [f64; 5])> = (0..400)
        .map(|k| {
            let u = (k as f64 * 0.3).sin();
            let x = [u, 0.12 * u, 0.3 * (k as f64 * 0.7).cos(), 0.0, 0.1];
            ((k + 1) as f64 * 0.05, x)
        })
        .collect();
    let mut grid = Grid::new(0.2, 500.0, None);
    let mut cells = vec![];
    for (d, x) in &signal {
        if let Some(c) = grid.add(*d, x) {
            cells.extend(c.cells);
        }
    }
    let (lo, hi) = (&bank.entries[0], &bank.entries[2]);
    assert_eq!((lo.speed, hi.speed, hi.condition), (10.0, 10.0, Some(1.0)));
    // The estimate of the taps blended at scale `s`, on the first cells.
    let blended = |s: f64| {
        let b = (s - 0.5) / 0.5;
        (1.0 - b) * direct(lo, 1, &cells) + b * direct(hi, 1, &cells)
    };
    let mut l = three_sensors(&bank, 0.0);
    for (d, x) in &signal {
        l.step(*d, 10.0, x, 0.0);
    }
    let s = l.contact_scale();
    assert!((s - (0.75 + 0.1 * 1.44f64.ln())).abs() < 0.02, "{s}");
    let want = blended(s);
    let (got, _) = l.causal(l.causal.points[1].distance).unwrap();
    assert!(
        (got - want).abs() < 1e-12 * want.abs().max(1.0),
        "{got} {want}"
    );
    // Told the Kalker scale: blended at it from the first cell (clamped to the trained range).
    for (told, at) in [(0.6, 0.6), (2.0, 1.0)] {
        let mut t = Learned::new(
            &bank,
            Choice {
                roll_rate: false,
                lag: 0.0,
                conicity: None,
                kalker: Some(told),
            },
        )
        .unwrap();
        let mut first = None;
        for (d, x) in &signal {
            t.step(*d, 10.0, x, 0.0);
            if first.is_none() && t.contact_scale() > 0.0 {
                first = Some(t.contact_scale());
            }
        }
        assert_eq!(first, Some(at), "told {told}");
        assert_eq!(t.contact_scale(), at);
        let want = blended(at);
        let (got, _) = t.causal(t.causal.points[1].distance).unwrap();
        assert!(
            (got - want).abs() < 1e-12 * want.abs().max(1.0),
            "told {told}: {got} {want}"
        );
    }
    // A bank without a contact model reports no scale.
    let plain = Learned::new(
        &sample_bank(),
        Choice {
            roll_rate: false,
            lag: 0.0,
            conicity: None,
            kalker: None,
        },
    )
    .unwrap();
    assert_eq!(plain.contact_scale(), 0.0);
}

/// A bank of the sample's causal taps at conicity 0.05 and three times them at 0.2, one contact
/// condition (Kalker 1), whose contact model reads `ln(conicity)` from the first feature
/// (`ln(conicity) = f0 + ln(0.1 / 1.44)`: 0.1 for the test signal's `f0 = ln 1.44`) and judges
/// the features against a forward model of zeros with unit precision over `level` 2.
fn coned_bank() -> Bank {
    use crate::learned::contact::{ConicityModel, ContactModel, FEATURES, SpeedModel};
    let mut bank = sample_bank();
    bank.entries.retain(|e| e.lag == 0 && e.speed == 10.0);
    let mut more = bank.entries.clone();
    for e in &mut bank.entries {
        e.condition = Some(1.0);
        e.conicity = Some(0.05);
    }
    for e in &mut more {
        e.condition = Some(1.0);
        e.conicity = Some(0.2);
        for w in &mut e.windows {
            w.taps.iter_mut().for_each(|t| *t *= 3.0);
        }
    }
    bank.entries.extend(more);
    let identity: Vec<f64> = (0..FEATURES * FEATURES)
        .map(|i| if i % (FEATURES + 1) == 0 { 1.0 } else { 0.0 })
        .collect();
    bank.contact = Some(ContactModel {
        band: [3.0, 25.0],
        extra_bands: vec![],
        memory: 10.0,
        range: [0.5, 1.0],
        speeds: vec![SpeedModel {
            speed: 10.0,
            coefficients: vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            rms_error: 0.1,
            conicity: Some(ConicityModel {
                coefficients: vec![1.0, 0.0, 0.0, 0.0, 0.0, (0.1f64 / 1.44).ln()],
                rms_error: 0.1,
                forward: vec![vec![0.0; 6]; FEATURES],
                precision: identity,
                level: 2.0,
                young: vec![],
            }),
            kalker_by_conicity: vec![],
            spectra: None,
        }],
        conicity_range: Some([0.05, 0.4]),
    });
    bank
}

#[test]
fn taps_are_blended_in_the_logarithm_of_the_conicity_estimated_or_told() {
    let bank = coned_bank();
    let run = |told: Option<f64>| {
        let mut l = Learned::new(
            &bank,
            Choice {
                roll_rate: false,
                lag: 0.0,
                conicity: told,
                kalker: None,
            },
        )
        .unwrap();
        let mut grid = Grid::new(0.2, 500.0, None);
        let (mut cells, mut d) = (vec![], 0.0);
        // 20 m, then on to the next cell at which the novelty is judged (every NOVELTY_EVERY).
        let mut k = 0;
        while k < 400 || l.to_novelty != crate::learned::contact::NOVELTY_EVERY {
            d += 0.05;
            let u = (k as f64 * 0.3).sin();
            let x = [u, 0.12 * u, 0.3 * (k as f64 * 0.7).cos(), 0.0, 0.1];
            if let Some(c) = grid.add(d, &x) {
                cells.extend(c.cells);
            }
            l.step(d, 10.0, &x, 0.0);
            k += 1;
        }
        (l, cells)
    };
    let (lo, hi) = (&bank.entries[0], &bank.entries[1]);
    for told in [None, Some(0.1), Some(0.3)] {
        let (l, cells) = run(told);
        let c = l.conicity();
        match told {
            Some(t) => assert_eq!(c, t),
            // ln(M_11 / M_00) = ln 1.44 up to the band-pass: 0.1.
            None => assert!((c / 0.1 - 1.0).abs() < 0.03, "{c}"),
        }
        let b = ((c / 0.05).ln() / 4f64.ln()).clamp(0.0, 1.0);
        let want = (1.0 - b) * direct(lo, 1, &cells) + b * direct(hi, 1, &cells);
        let (got, std) = l.causal(l.causal.points[1].distance).unwrap();
        assert!(
            (got - want).abs() < 1e-12 * want.abs().max(1.0),
            "told {told:?}: {got} {want}"
        );
        // The novelty: the features' squared length over the level (forward model zero,
        // unit precision), the memory full; alignment_std grown by its square root above 1.
        let m = l.moments.as_ref().unwrap();
        let f = m.features(0).unwrap();
        let want = f.iter().map(|v| v * v).sum::<f64>() / 2.0;
        assert!(
            (l.novelty() - want).abs() < 1e-9 * want,
            "{} {want}",
            l.novelty()
        );
        // Told 0.3, beyond the bank's 0.2 by more than CONICITY_MARGIN: outside whatever the
        // novelty says (at once: not waiting for the novelty to be judged), and the std grown by
        // the distance ln(0.3 / 0.2) too. Estimated (about 0.1, inside 0.05-0.2): no growth.
        assert_eq!(l.outside_training(), want > 1.0 || told == Some(0.3));
        let grow = match told {
            Some(0.3) => (1.0 + (1.5f64.ln() / CONICITY_ERROR_SCALE).powi(2)).sqrt(),
            _ => 1.0,
        };
        assert!(
            (l.conicity_growth() - grow).abs() < 1e-12,
            "{}",
            l.conicity_growth()
        );
        // The outputs: averaged with the Kalman filter's (here 0, with a deviation of 1) by
        // its share at this novelty; the deviation the learned one, grown.
        let e = l.estimate(l.causal.points[1].distance, (0.0, 1.0));
        let w = crate::learned::fallback_share(want);
        assert!(
            (e.std - std * want.max(1.0).sqrt().max(grow)).abs() < 1e-12 * e.std,
            "{} {std} {w}",
            e.std
        );
        assert!(
            (e.alignment - (1.0 - w) * got).abs() < 1e-12 * got.abs(),
            "{} {got} {w}",
            e.alignment
        );
    }
    assert_eq!(
        three_sensors(&bank, 0.0).selected_conicities(),
        &[0.05, 0.2]
    );
}

#[test]
fn a_bank_whose_entries_mix_conicities_and_none_is_refused() {
    let mut bank = coned_bank();
    bank.entries[0].conicity = None;
    let e = Bank::parse(&bank.to_bytes(), std::path::Path::new("c.taps"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("conicity on every entry"), "{e}");
    let mut bank = coned_bank();
    bank.contact.as_mut().unwrap().speeds[0].conicity = None;
    let e = Bank::parse(&bank.to_bytes(), std::path::Path::new("c.taps"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("conicity model missing"), "{e}");
}

#[test]
fn before_its_window_fills_the_lagged_output_is_the_causal_estimate_made_lag_behind() {
    let mut bank = sample_bank();
    // Fixed-lag windows from 5 points back only: the causal ones start 1.2 m earlier.
    for e in bank.entries.iter_mut().filter(|e| e.lag > 0) {
        e.windows.retain(|w| w.past == 5);
    }
    let mut l = three_sensors(&bank, 0.6);
    let (mut d, mut made) = (0.0, vec![]);
    let mut checked = 0;
    for k in 0..40 {
        d = (k + 1) as f64 * 0.05;
        l.step(d, 15.0, &[(k as f64 * 0.7).sin(), 0.0, 0.0, 0.0, 0.1], 0.0);
        if let Some(p) = l.causal.points.last()
            && made.last().map(|m: &Point| m.distance) != Some(p.distance)
        {
            made.push(*p);
        }
        // Before the fixed-lag window fills, every position lag behind that lies between
        // two causal estimates gets their linear interpolation.
        let at = d - 0.6;
        if l.lagged.points.is_empty()
            && let Some(i) = made.iter().position(|m| m.distance >= at)
            && i > 0
        {
            let (a, b) = (made[i - 1], made[i]);
            let want =
                a.value + (at - a.distance) / (b.distance - a.distance) * (b.value - a.value);
            let (got, std) = l.lagged(d).unwrap();
            assert!((got - want).abs() < 1e-12, "at {d} m: {got} {want}");
            assert_eq!(std, b.std);
            checked += 1;
        }
    }
    assert!(checked >= 2, "{checked} positions checked");
    assert!(
        !l.lagged.points.is_empty(),
        "the lagged window filled by {d} m"
    );
}

#[test]
fn outside_the_speed_range_there_is_no_estimate_and_it_resumes_inside() {
    let bank = sample_bank();
    let mut l = three_sensors(&bank, 0.0);
    assert_eq!(l.speed_range(), (10.0, 20.0));
    let mut d = 0.0;
    for _ in 0..100 {
        d += 0.05;
        l.step(d, 25.0, &[1.0; 5], 0.0);
    }
    assert!(!l.in_range() && l.causal(d).is_none());
    for _ in 0..10 {
        d += 0.05;
        l.step(d, 15.0, &[1.0; 5], 0.0);
    }
    assert!(l.in_range() && l.causal(d).is_some());
}

#[test]
fn unavailable_choices_are_refused_by_name() {
    let bank = sample_bank();
    let e = Learned::new(
        &bank,
        Choice {
            roll_rate: true,
            lag: 0.0,
            conicity: None,
            kalker: None,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("four sensors"), "{e}");
    let e = Learned::new(
        &bank,
        Choice {
            roll_rate: false,
            lag: 10.0,
            conicity: None,
            kalker: None,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("lag = 10 m") && e.contains("0.6"), "{e}");
}

#[test]
fn extrapolation_is_linear_and_at_most_one_cell_ahead() {
    let mut t = Track::default();
    t.push(Point {
        value: 1.0,
        std: 0.1,
        distance: 1.0,
    });
    t.push(Point {
        value: 2.0,
        std: 0.2,
        distance: 1.2,
    });
    assert!((t.at(1.3).unwrap().0 - 2.5).abs() < 1e-12);
    assert!((t.at(5.0).unwrap().0 - 3.0).abs() < 1e-12);
    assert_eq!(t.at(1.0).unwrap(), (2.0, 0.2));
}

#[test]
fn where_no_learned_estimate_was_made_the_lagged_output_is_the_kalman_one_made_there() {
    let mut bank = sample_bank();
    // Causal windows from 5 points back only: the first 1.2 m have the Kalman estimate alone.
    for e in &mut bank.entries {
        e.windows.retain(|w| w.past == 5);
    }
    let mut l = three_sensors(&bank, 0.6);
    // A Kalman estimate linear in distance: the delay line's interpolation between the cells'
    // closings gives it back exactly at any position in between.
    let kalman = |d: f64| 10.0 + d;
    let (mut d, mut checked) = (0.0, [0, 0]);
    // Start (15 m/s, inside the range), then 25 m/s (outside), then back inside.
    for k in 0..200 {
        let speed = if (80..160).contains(&k) { 25.0 } else { 15.0 };
        d += 0.05;
        let x = [(k as f64 * 0.7).sin(), 0.0, 0.0, 0.0, kalman(d)];
        l.step(d, speed, &x, 0.5);
        let at = d - 0.6;
        let e = l.estimate(d, (kalman(d), 0.5));
        let (got, std) = (e.lagged, e.lagged_std);
        // The first metre (Kalman points from 0.2 m to 1.0 m) and well inside the excursion.
        let first = (0.2..=1.0).contains(&at);
        let outside = (80 + 12 + 4..160).contains(&k);
        if first || outside {
            assert!(
                (got - kalman(at)).abs() < 1e-9 && std == 0.5,
                "step {k}, at {at} m: {got} (std {std}), made there {}",
                kalman(at)
            );
            checked[usize::from(outside)] += 1;
        }
    }
    assert!(checked[0] >= 10 && checked[1] >= 50, "{checked:?}");
    // Back inside, the learned fixed-lag estimate resumed.
    assert!(!l.lagged.points.is_empty() && l.in_range());
}

#[test]
fn while_the_speed_changes_each_cell_is_rescaled_to_the_current_speed() {
    let bank = sample_bank();
    let mut l = three_sensors(&bank, 0.0);
    // Speed rising from 4 m/s (below the bank's 10 m/s: its cells count as 10 m/s) to 16 m/s.
    let speed = |k: usize| 4.0 + 0.06 * k as f64;
    let mut grid = Grid::new(0.2, 500.0, None);
    let (mut cells, mut speeds) = (vec![], vec![]);
    let mut d = 0.0;
    for k in 0..200 {
        d += 0.05;
        let x = sample(k);
        if let Some(c) = grid.add(d, &x) {
            speeds.extend(c.cells.iter().map(|_| speed(k)));
            cells.extend(c.cells);
        }
        l.step(d, speed(k), &x, 0.0);
    }
    let now = speed(199);
    assert!(now > 15.0 && *speeds.last().unwrap() == now);
    // Each cell as it would have been at the current speed.
    let rescaled: Vec<[f64; 5]> = cells
        .iter()
        .zip(&speeds)
        .map(|(c, v)| std::array::from_fn(|i| c[i] * (now / v.max(10.0)).powf(TAP_SPEED_POWER[i])))
        .collect();
    let a = (now - 10.0) / 10.0;
    let want = (1.0 - a) * direct(&bank.entries[0], 1, &rescaled)
        + a * direct(&bank.entries[1], 1, &rescaled);
    let last = *l.causal.points.last().unwrap();
    assert!(
        (last.value - want).abs() < 1e-12 * want.abs().max(1.0),
        "{} {want}",
        last.value
    );
    // The accelerations' quotient matters: without it the estimate differs.
    let plain =
        (1.0 - a) * direct(&bank.entries[0], 1, &cells) + a * direct(&bank.entries[1], 1, &cells);
    assert!(
        (plain - want).abs() > 1e-3 * want.abs().max(1e-3),
        "{plain} {want}"
    );
}

#[test]
fn the_speed_factors_are_the_documented_powers() {
    for v in [0.3, 5.0, 12.5, 30.0] {
        let f = speed_factors(v);
        for (c, p) in TAP_SPEED_POWER.iter().enumerate() {
            assert!((f[c] - v.powf(*p)).abs() <= 1e-14 * v.powf(*p), "{v} {c}");
        }
    }
}

/// The judged conicity: nothing until the features' memory is full, then the running mean of
/// `ln(conicity_estimate)` over the distance since, exponential once CONICITY_MEMORY is
/// reached; `outside_training` and the std's growth read it, not the estimate of the moment.
#[test]
fn the_judged_conicity_is_a_running_mean_of_the_estimate_from_a_full_memory() {
    let bank = coned_bank();
    let mut l = three_sensors(&bank, 0.0);
    let ds = l.grid.step_length();
    let mut d = 0.0;
    let mut push = |l: &mut Learned, c: f64, full: bool| {
        d += ds;
        l.conicity = c;
        l.judge_conicity(d, 1, full);
    };
    // Far beyond the bank's 0.05-0.2, but the memory not full: not judged.
    push(&mut l, 1.0, false);
    assert_eq!((l.conicity_distance(), l.conicity_growth()), (0.0, 1.0));
    // 0.4 then 0.05 over equal steps: the mean of their logarithms (0.14), inside the bank.
    push(&mut l, 0.4, true);
    assert!((l.conicity_distance() - 2f64.ln()).abs() < 1e-12);
    push(&mut l, 0.05, true);
    let mean = (0.4f64.ln() + 0.05f64.ln()) / 2.0;
    assert!((l.judged_conicity.unwrap() - mean).abs() < 1e-12);
    assert_eq!(l.conicity_distance(), 0.0);
    // Beyond CONICITY_MEMORY, each step moves it by step / memory of the way.
    for _ in 0..(CONICITY_MEMORY / ds) as usize + 10 {
        push(&mut l, 0.1, true);
    }
    let before = l.judged_conicity.unwrap();
    push(&mut l, 0.3, true);
    let want = before + ds / CONICITY_MEMORY * (0.3f64.ln() - before);
    assert!((l.judged_conicity.unwrap() - want).abs() < 1e-12);
    // Told: the told conicity at once, memory or not.
    let mut told = Learned::new(
        &bank,
        Choice {
            roll_rate: false,
            lag: 0.0,
            conicity: Some(0.3),
            kalker: None,
        },
    )
    .unwrap();
    told.conicity = 0.3;
    told.judge_conicity(0.2, 1, false);
    assert!((told.conicity_distance() - 1.5f64.ln()).abs() < 1e-12);
    assert!(told.beyond_conicities());
}

/// A bank's long-wave stage: with one tap, on the estimate's newest band-passed value, the
/// causal output is the stage-free one plus that tap (blended in speed) times the stage-free
/// estimate less its mean so far, band-passed, from where the stage's start ramp ends;
/// nothing before it begins; the fixed-lag output is the stage-free one (past the lag's
/// start-up, when it is the delayed causal output).
#[test]
fn the_stage_adds_its_taps_times_the_band_passed_estimate_to_the_causal_output() {
    use super::super::stage::{self, LAGS, StageBank, StageEntry};
    let plain = sample_bank();
    let mut staged = plain.clone();
    let entry = |speed: f64, tap: f64| {
        let mut taps = vec![0.0; 4 * LAGS];
        taps[3 * LAGS] = tap; // the estimate, lag 0
        StageEntry {
            speed,
            channels: ["ws_acc_y", "ws_yaw_rate", "frame_acc_y", stage::ESTIMATE]
                .map(String::from)
                .to_vec(),
            ridge: 1e-6,
            validation: [0.1, 0.09],
            taps,
        }
    };
    staged.stage = Some(StageBank {
        highpass: stage::HIGHPASS,
        lowpass: stage::LOWPASS,
        spacing: stage::SPACING,
        lags: LAGS,
        estimate_highpass_order: stage::ESTIMATE_HIGHPASS_ORDER,
        entries: vec![entry(20.0, 1.0), entry(10.0, 0.5)],
    });
    let (mut a, mut b) = (three_sensors(&plain, 0.6), three_sensors(&staged, 0.6));
    assert!(!a.has_stage() && b.has_stage());
    // 12.5 m/s, 0.05 m a sample: the tap blends to 0.75 * 0.5 + 0.25 * 1.0.
    let tap = 0.625;
    let (mut filters, mut extra) = (stage::design(0.2), stage::estimate_highpass(0.2));
    let mut grid = Grid::new(0.2, 500.0, None);
    let (mut d, mut last, mut sum, mut cells) = (0.0, f64::NAN, 0.0, 0.0);
    let [start, full] = stage::START_RAMP;
    for k in 0..12_000 {
        d += 0.05;
        // Long waves too, for the band-pass to pass.
        let x = [
            (k as f64 * 0.3).sin() + (k as f64 * 0.002).sin(),
            0.0,
            0.0,
            0.0,
            (k as f64 * 0.11).cos() + (k as f64 * 0.0015).cos() + 3.0,
        ];
        a.step(d, 12.5, &x, 0.0);
        b.step(d, 12.5, &x, 0.0);
        let Some(closed) = grid.add(d, &x) else {
            continue;
        };
        assert_eq!(closed.cells.len(), 1);
        // The stage's input: the taps' estimate where they made one, else the Kalman channel.
        let made = a
            .causal
            .points
            .last()
            .filter(|p| p.distance == closed.distance);
        // Its mean since the start taken out, then band-passed.
        let e = made.map_or(x[4], |p| p.value);
        (sum, cells) = (sum + e, cells + 1.0);
        let u = filters
            .iter_mut()
            .fold(extra.step(e - sum / cells), |v, f| f.step(v));
        let (Some(p), Some(q)) = (made, b.causal.points.last()) else {
            continue;
        };
        last = p.distance;
        if p.distance < start {
            assert_eq!(q.value, p.value, "at {} m", p.distance);
        } else if p.distance > full + 1.0 {
            let want = p.value + tap * u;
            assert!(
                (q.value - want).abs() < 1e-12 * want.abs().max(1.0),
                "at {} m: {} {want}",
                p.distance,
                q.value
            );
        }
        if p.distance > 2.0 {
            assert_eq!(a.lagged(d), b.lagged(d), "at {d} m");
        }
    }
    assert!(last > 590.0);
}
