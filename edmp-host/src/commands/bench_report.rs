//! `edmp-host bench-report`: compares runs of `edmp-host bench` (their `results.jsonl`) and
//! writes `report.md` with the paper's ablations where the runs allow them, plus charts. The
//! ablations use only the EDMP runs with the first EDMP run's settings (sampler, steps,
//! limits, boxes), so that they differ in their guides alone:
//! - the first `--charts` runs per family (`success.png`), and the planning-time distribution
//!   of the runs planned one problem at a time (`time.png`: only their times compare);
//! - Table III: the 12-guide ensemble against the average of the single-guide runs (success
//!   and ACSM diversity);
//! - Figure 6: success against the number of guides (`guides.png`), from runs with 1, 2, 3, 4,
//!   6 or 12 guides;
//! - Figure 7: each guide's share of the ensemble's successes (`winners.png`).

use crate::commands::bench::{Record, TABLE_HEADER, cdf, families, read_results, table_row};
use crate::plots;
use core::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `edmp-host bench-report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folders of `edmp-host bench` runs.
    #[arg(required = true)]
    runs: Vec<PathBuf>,
    /// Folder for `report.md` and the charts (created).
    #[arg(short, long)]
    out: PathBuf,
    /// Runs drawn in the success chart (the first N given; the tables have them all).
    #[arg(long, default_value_t = 6)]
    charts: usize,
}

struct Run {
    label: String,
    records: Vec<Record>,
}

impl Run {
    fn success(&self, family: Option<&str>) -> f64 {
        let rows: Vec<&Record> = self
            .records
            .iter()
            .filter(|r| family.is_none_or(|f| r.family == f))
            .collect();
        100.0 * rows.iter().filter(|r| r.solved()).count() as f64 / rows.len().max(1) as f64
    }

    fn acsm(&self) -> Option<f64> {
        let v: Vec<f64> = self.records.iter().filter_map(|r| r.acsm).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    }

    /// EDMP's guides in this run (empty for other planners).
    fn guides(&self) -> &[u8] {
        self.records.first().map_or(&[], |r| &r.guides)
    }

    /// EDMP's settings besides the guides (empty for other planners).
    fn config(&self) -> &str {
        self.records.first().map_or("", |r| &r.config)
    }
}

/// Writes the report and charts.
pub fn run(args: &Args) -> Result<(), String> {
    let runs: Vec<Run> = args
        .runs
        .iter()
        .map(|dir| {
            let records = read_results(dir)?;
            let label = records
                .first()
                .map(|r| r.planner.clone())
                .ok_or_else(|| format!("{}: no results", dir.display()))?;
            Ok(Run { label, records })
        })
        .collect::<Result<_, String>>()?;
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let families = families(&runs[0].records);
    let mut md = String::new();

    // Every run, all families together, then solved per family.
    let _ = writeln!(md, "## Runs\n\n{}", TABLE_HEADER.replacen("| |", "| run |", 1));
    for run in &runs {
        let _ = writeln!(md, "{}", table_row(&run.label, &run.records.iter().collect::<Vec<_>>()));
    }
    let _ = write!(md, "\n| run | {} | all |\n|---|", families.join(" | "));
    let _ = writeln!(md, "{}---|", "---|".repeat(families.len()));
    for run in &runs {
        let cells: Vec<String> = families
            .iter()
            .map(|f| format!("{:.1}", run.success(Some(f))))
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} |",
            run.label,
            cells.join(" | "),
            run.success(None)
        );
    }
    let mut categories = families.clone();
    categories.push("all".to_owned());
    let series: Vec<(String, Vec<f64>)> = runs
        .iter()
        .take(args.charts.max(1))
        .map(|run| {
            let mut v: Vec<f64> = families.iter().map(|f| run.success(Some(f))).collect();
            v.push(run.success(None));
            (run.label.clone(), v)
        })
        .collect();
    plots::grouped_bars(
        &args.out.join("success.png"),
        "Solved per family",
        "solved (%)",
        &categories,
        &series,
        100.0,
    )?;
    let _ = writeln!(
        md,
        "\n![solved per family, the first {} runs](success.png)",
        series.len()
    );
    let curves: Vec<(String, Vec<(f64, f64)>)> = runs
        .iter()
        .filter(|r| r.records.first().is_some_and(|x| x.serial))
        .map(|r| (r.label.clone(), cdf(&r.records, "")))
        .collect();
    if !curves.is_empty() {
        let title = "Planning time, all problems, one plan at a time";
        plots::time_distribution(&args.out.join("time.png"), title, &curves)?;
        let _ = writeln!(md, "\n![planning time](time.png)");
    }

    // The ablations compare EDMP runs that differ in their guides alone.
    let reference = runs.iter().find(|r| !r.guides().is_empty()).map_or("", |r| r.config());
    let comparable: Vec<&Run> = runs
        .iter()
        .filter(|r| !r.guides().is_empty() && r.config() == reference)
        .collect();
    // Table III: the ensemble against the average single guide.
    let singles: Vec<&Run> = comparable.iter().copied().filter(|r| r.guides().len() == 1).collect();
    let ensembles: Vec<&Run> = comparable.iter().copied().filter(|r| r.guides().len() == 12).collect();
    if !singles.is_empty() && !ensembles.is_empty() {
        let _ = writeln!(
            md,
            "\n## Ensemble against single guides (the paper's Table III)\n\n| | solved (%) | ACSM (lower: more diverse) |\n|---|---|---|"
        );
        let mean = |f: &dyn Fn(&Run) -> Option<f64>| {
            let v: Vec<f64> = singles.iter().filter_map(|r| f(r)).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let _ = writeln!(
            md,
            "| average of {} single-guide runs | {:.1} | {:.4} |",
            singles.len(),
            mean(&|r| Some(r.success(None))),
            mean(&|r| r.acsm())
        );
        for e in &ensembles {
            let _ = writeln!(
                md,
                "| {} | {:.1} | {} |",
                e.label,
                e.success(None),
                e.acsm().map_or("–".to_owned(), |a| format!("{a:.4}"))
            );
        }
        let _ = writeln!(md, "\n| single guide | solved (%) | ACSM |\n|---|---|---|");
        for s in &singles {
            let _ = writeln!(
                md,
                "| {} | {:.1} | {} |",
                s.guides()[0],
                s.success(None),
                s.acsm().map_or("–".to_owned(), |a| format!("{a:.4}"))
            );
        }
    }

    // Figure 6: success against the number of guides.
    let mut by_count: Vec<(usize, Vec<f64>)> = Vec::new();
    for run in &comparable {
        let n = run.guides().len();
        match by_count.iter_mut().find(|(c, _)| *c == n) {
            Some((_, v)) => v.push(run.success(None)),
            None => by_count.push((n, vec![run.success(None)])),
        }
    }
    by_count.sort_by_key(|(n, _)| *n);
    if by_count.len() >= 2 {
        let _ = writeln!(
            md,
            "\n## Success against the number of guides (the paper's Figure 6)\n\n| guides | runs | mean solved (%) |\n|---|---|---|"
        );
        let points: Vec<(f64, f64)> = by_count
            .iter()
            .map(|(n, v)| (*n as f64, v.iter().sum::<f64>() / v.len() as f64))
            .collect();
        for ((n, v), (_, mean)) in by_count.iter().zip(&points) {
            let _ = writeln!(md, "| {n} | {} | {mean:.1} |", v.len());
        }
        let lo = points.iter().map(|p| p.1).fold(100.0, f64::min);
        plots::lines(
            &args.out.join("guides.png"),
            "Solved against the number of guides (12 rows in every run)",
            "guides",
            "solved (%)",
            (0.5, 12.5),
            ((lo - 10.0).max(0.0), 100.0),
            &[("mean over runs with that many guides".to_owned(), points)],
            true,
        )?;
        let _ = writeln!(md, "\n![success against guides](guides.png)");
    }

    // Figure 7: each guide's share of the ensemble's successes.
    if let Some(e) = ensembles.first() {
        let guides = e.guides().to_vec();
        let solved: Vec<&Record> = e.records.iter().filter(|r| r.solved()).collect();
        let won: Vec<f64> = guides
            .iter()
            .map(|g| 100.0 * solved.iter().filter(|r| r.guide == Some(*g)).count() as f64 / solved.len().max(1) as f64)
            .collect();
        let free: Vec<f64> = guides
            .iter()
            .map(|g| {
                let n = e
                    .records
                    .iter()
                    .filter(|r| r.candidates.iter().any(|c| c.guide == *g && c.free == Some(true)))
                    .count();
                100.0 * n as f64 / e.records.len().max(1) as f64
            })
            .collect();
        let _ = writeln!(
            md,
            "\n## Each guide's share (the paper's Figure 7), {}\n\n| guide | share of successes won (%) | problems where its candidate is free (%) |\n|---|---|---|",
            e.label
        );
        for ((g, w), f) in guides.iter().zip(&won).zip(&free) {
            let _ = writeln!(md, "| {g} | {w:.1} | {f:.1} |");
        }
        let unjudged = e
            .records
            .iter()
            .filter(|r| r.candidates.iter().any(|c| c.free.is_none()))
            .count();
        if unjudged > 0 {
            let _ = writeln!(
                md,
                "\n{unjudged} problems have candidates the planner did not judge (it stops at the winner \
                 unless `bench --judge-every`): the free column counts them as not free."
            );
        }
        let unmade = e
            .records
            .iter()
            .filter(|r| guides.iter().any(|g| !r.candidates.iter().any(|c| c.guide == *g)))
            .count();
        if unmade > 0 {
            let _ = writeln!(
                md,
                "\n{unmade} problems were solved before their last wave of guides ran (`PlanConfig::waves`; \
                 `bench --waves 1` makes every guide's candidate, as the paper): the free column counts \
                 the guides that did not run as not free."
            );
        }
        let names: Vec<String> = guides.iter().map(u8::to_string).collect();
        plots::grouped_bars(
            &args.out.join("winners.png"),
            "Each guide: share of successes won, problems where its candidate is free",
            "%",
            &names,
            &[
                ("share of the ensemble's successes won".to_owned(), won),
                ("problems where its candidate is free".to_owned(), free),
            ],
            100.0,
        )?;
        let _ = writeln!(md, "\n![each guide's share](winners.png)");
    }
    let path = args.out.join("report.md");
    std::fs::write(&path, &md).map_err(|e| format!("{}: {e}", path.display()))?;
    crate::commands::print_stdout(&md)
}
