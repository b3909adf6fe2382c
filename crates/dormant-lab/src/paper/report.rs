//! The output of `dormant bench paper`: `paper.json` (the whole [`PaperReport`]), `paper.md`
//! (the paper's claims against our numbers, then each workload's tables) and one figure per
//! workload under `figures/`. Every file is written atomically.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::plot::write_workload_png;
use super::{PaperReport, Reproduction, WorkloadReport};
use crate::report::ReportError;
use dormant::residency::{CacheStats, IntegrationForm, IntegrationPolicy};

/// Writes `paper.json`, `paper.md` and `figures/<workload>.png` into `dir` (created if
/// missing) and returns the paths written.
pub fn write_paper(report: &PaperReport, dir: &Path) -> Result<Vec<PathBuf>, ReportError> {
    let figures = dir.join("figures");
    std::fs::create_dir_all(&figures)
        .map_err(|source| ReportError::Write { path: figures.clone(), source })?;
    let mut written = Vec::new();
    for w in &report.workloads {
        let path = figures.join(format!("{}.png", w.name));
        write_workload_png(w, &path)?;
        written.push(path);
    }
    // Through a Value, as `--json` writes it, so both print f32 fields alike.
    let value = crate::bench::bench_json(report);
    let json = serde_json::to_string_pretty(&value).expect("JSON values serialise");
    let mut md = paper_markdown(report);
    md.push_str(&regime_section(dir)?);
    for (name, text) in [("paper.json", json), ("paper.md", md)] {
        let path = dir.join(name);
        dormant::atomic_file::write_atomic(&path, text.as_bytes())
            .map_err(|source| ReportError::Write { path: path.clone(), source })?;
        written.push(path);
    }
    Ok(written)
}

/// The regime map's section of `paper.md`, when `dir/regimes/` holds one: the reading of it
/// (`summary.md`, written by hand after a run of `dormant bench regimes --out
/// dir/regimes`), then its figures and measured table. Empty when there is none.
fn regime_section(dir: &Path) -> Result<String, ReportError> {
    let regimes = dir.join(REGIMES_DIR);
    let read = |name: &str| {
        let path = regimes.join(name);
        match std::fs::read_to_string(&path) {
            Ok(text) => Ok(Some(text)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(source) => Err(ReportError::Read { path, source }),
        }
    };
    let Some(table) = read("regimes.md")? else { return Ok(String::new()) };
    let mut md = String::from("## Where integration pays (`dormant bench regimes`)\n\n");
    if let Some(summary) = read("summary.md")? {
        md.push_str(summary.trim_end());
        md.push_str("\n\n");
    }
    md.push_str(&format!("![regime map]({REGIMES_DIR}/regimes.png)\n\n"));
    md.push_str(&format!("![reuse, integration and both]({REGIMES_DIR}/regimes-reuse.png)\n\n"));
    md.push_str(table.trim_end());
    md.push('\n');
    Ok(md)
}

/// Where `paper.md` looks for the regime map, under its own directory.
const REGIMES_DIR: &str = "regimes";

fn verdict(v: Reproduction) -> &'static str {
    match v {
        Reproduction::Reproduced => "reproduced",
        Reproduction::Partly => "partly",
        Reproduction::NotReproduced => "not reproduced",
        Reproduction::NoData => "no data",
    }
}

/// `paper.md`: generated, so every number in it is measured by the run that wrote it.
pub fn paper_markdown(report: &PaperReport) -> String {
    let mut md = String::new();
    let load = |l: Option<f64>| l.map_or("?".into(), |l| format!("{l:.1}"));
    let _ = writeln!(md, "# The paper's experiments, reproduced\n");
    let _ = writeln!(
        md,
        "Written by `dormant bench paper` (preset `{:?}`) in {:.1} min on {} threads; 1-minute load \
         average {} at the start and {} at the end. Each workload was simulated once; every backend \
         then rendered the same trajectory under `never`, `always` and `auto`, with the geometry cache \
         on and off, in lockstep (each frame by all five configurations before the next), so machine \
         load falls on all of them alike. Frame time is the whole frame: reactivate + integrate + \
         update + commit + trace. Ratios are defined in docs/performance.md.\n",
        report.preset,
        report.wall_s / 60.0,
        report.threads,
        load(report.load_average[0]),
        load(report.load_average[1]),
    );

    let _ = writeln!(
        md,
        "How the claims map onto our measurements:\n\n\
         - **Frame-rate gain**: `settled_speedup` is `never`'s mean frame time over `auto`'s (cache on) \
         over the settled frames, where at least 90% of the bodies present are asleep (n/a when no frame \
         settles); `run_speedup` is the same over every rendered frame.\n\
         - **Insertion against rebuild**: `rebuild_over_insert` is a from-scratch build of `always`'s \
         final static scene over the mean cost of integrating one island during the run.\n\
         - **Cache requests at 90-99%**: dormant asks the geometry cache for a static scene when \
         integrated islands wake; the request is the set of integrated islands still asleep, and the \
         served entry is the largest cached subset of it. `partial_hit_90_99_fraction` is the share of \
         `auto`'s requests whose entry held 90-99% of the requested islands. Integrating a new island \
         is an incremental insert into the current scene and is not counted as a request.\n"
    );
    let _ = writeln!(md, "## The paper's claims against our measurements\n");
    let _ = writeln!(md, "| claim | paper | workload | backend | metric | ours | rule | verdict |");
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | ---: | --- | --- |");
    for c in &report.claims {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | `{}` | {} | {} | **{}** |",
            c.claim,
            c.paper,
            c.workload,
            c.backend,
            c.metric,
            num(c.measured),
            c.rule,
            verdict(c.verdict)
        );
    }
    let _ = writeln!(md);
    for w in &report.workloads {
        workload_section(&mut md, w);
    }
    md
}

fn num(v: f64) -> String {
    if !v.is_finite() {
        "n/a".into()
    } else if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

fn workload_section(md: &mut String, w: &WorkloadReport) {
    workload_summary(md, w);
    ratios_table(md, w);
    stage_table(md, w);
    settled_stages(md, w);
    cache_table(md, w);
    accel_table(md, w);
}

/// The workload's size, islands, rendered frames and figure.
fn workload_summary(md: &mut String, w: &WorkloadReport) {
    let s = &w.size;
    let i = &w.islands;
    let _ = writeln!(md, "## {}: {}\n", w.name, w.description);
    let _ = writeln!(
        md,
        "- {} objects simulated for {} frames in {:.0} s; {:.1}% of the bodies asleep at the end.\n\
         - Islands: {} formed, {} woken, {} asleep at the end; size mean {:.1}, largest {}; mean \
         sleep {:.0} frames.\n\
         - {} rendered ({} frames) at {}x{}, shaded preview (camera and shadow rays), 1 spp.\n",
        s.count,
        s.frames,
        w.simulate_s,
        100.0 * i.asleep_fraction_at_end,
        i.islands_formed,
        i.islands_woken,
        i.islands_asleep_at_end,
        i.size_mean,
        i.size_max,
        i.mean_sleep_frames_all,
        every(s.frame_step),
        w.runs.first().map_or(0, |r| r.integration.frames_rendered),
        s.width,
        s.height,
    );
    let _ = writeln!(md, "![{}](figures/{}.png)\n", w.name, w.name);
}

/// The integration ratios per backend.
fn ratios_table(md: &mut String, w: &WorkloadReport) {
    let _ = writeln!(md, "### Integration ratios\n");
    let _ = writeln!(
        md,
        "| backend | settled_speedup | run_speedup | auto_over_best | rebuild_over_insert | \
         partial_hit_90_99_fraction | wall (s) |"
    );
    let _ = writeln!(md, "| --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    for run in &w.runs {
        let r = &run.integration.ratios;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {:.0} |",
            run.backend,
            num(r.settled_speedup),
            num(r.run_speedup),
            num(r.auto_over_best),
            num(r.rebuild_over_insert),
            num(r.partial_hit_90_99_fraction),
            run.wall_s
        );
    }
    let _ = writeln!(md);
}

/// Mean frame and settled stage times per backend and configuration.
fn stage_table(md: &mut String, w: &WorkloadReport) {
    let _ = writeln!(md, "### Where the time goes\n");
    let _ = writeln!(
        md,
        "Mean ms per frame over the whole run and over the settled frames (at least 90% of the \
         bodies present asleep), and the settled frame by stage.\n"
    );
    let _ = writeln!(
        md,
        "| backend | configuration | frame (all) | frame (settled) | reactivate | integrate | update | \
         commit | trace | islands integrated | reactivated | from cache | instances at end |"
    );
    let _ = writeln!(
        md,
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for run in &w.runs {
        for p in &run.integration.runs {
            let st = &p.settled;
            let _ = writeln!(
                md,
                "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} |",
                run.backend,
                p.name,
                p.all.frame_ms,
                st.frame_ms,
                st.stages.reactivate_ms,
                st.stages.integrate_ms,
                st.stages.update_ms,
                st.stages.commit_ms,
                st.stages.trace_ms,
                p.islands_integrated,
                p.islands_reactivated,
                p.reactivations_from_cache,
                p.instances_at_end
            );
        }
    }
    let _ = writeln!(md);
}

/// What `auto` saves or costs against `never` per settled frame, by stage.
fn settled_stages(md: &mut String, w: &WorkloadReport) {
    for run in &w.runs {
        let find = |policy| run.integration.cache_on(policy);
        let (Some(never), Some(auto)) = (find(IntegrationPolicy::Never), find(IntegrationPolicy::Auto))
        else {
            continue;
        };
        if never.settled.frames == 0 {
            let _ = writeln!(md, "- {}: no rendered frame settled (90% of the bodies asleep).", run.backend);
            continue;
        }
        let (n, a) = (&never.settled.stages, &auto.settled.stages);
        let _ = writeln!(
            md,
            "- {}, settled frames: `never` commits the top level in {:.2} ms and traces in {:.2} ms; \
             `auto` commits in {:.2} ms and traces in {:.2} ms, plus {:.2} ms of reactivation, \
             integration and updates. Against `never`, `auto` {} of commit and {} of trace per frame.",
            run.backend,
            n.commit_ms,
            n.trace_ms,
            a.commit_ms,
            a.trace_ms,
            a.structure_ms(),
            saves_or_costs(n.commit_ms - a.commit_ms),
            saves_or_costs(n.trace_ms - a.trace_ms),
        );
    }
    let _ = writeln!(md);
}

/// The geometry cache's requests by served fraction (`auto`, cache on).
fn cache_table(md: &mut String, w: &WorkloadReport) {
    let _ = writeln!(md, "### Geometry cache (`auto baked`, cache on)\n");
    let _ = writeln!(
        md,
        "Requests by the fraction of the requested islands the served entry held.\n\n| backend | requests | \
         full | partial | miss | {} |",
        CacheStats::FRACTION_BUCKETS.join(" | ")
    );
    let _ = writeln!(md, "| --- |{}", " ---: |".repeat(4 + CacheStats::FRACTION_BUCKETS.len()));
    for run in &w.runs {
        let Some(auto) = run.integration.run_of(IntegrationPolicy::Auto, IntegrationForm::Baked) else {
            continue;
        };
        let c = &auto.cache_stats;
        let buckets: Vec<String> = c.fraction_histogram.iter().map(u64::to_string).collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} |",
            run.backend,
            c.requests,
            c.full,
            c.partial,
            c.miss,
            buckets.join(" | ")
        );
    }
    let _ = writeln!(md);
}

/// The accelerator benchmark on the last frame.
fn accel_table(md: &mut String, w: &WorkloadReport) {
    let a = &w.accel;
    let r = &a.ratios;
    let _ = writeln!(md, "### Accelerators on the last frame\n");
    let _ = writeln!(
        md,
        "{} static triangles and {} instances ({} instanced triangles); {} primary and {} bounce \
         rays; the inserted island is 1% of the bodies.\n",
        a.static_triangles, a.instances, a.instanced_triangles, a.primary_rays, a.bounce_rays
    );
    let _ = writeln!(
        md,
        "| bvh_over_embree_trace | bvh_over_embree_high_trace | bvh_over_embree_build | \
         bvh_rebuild_over_insert | bvh_insert_sah_over_rebuild | embree_rebuild_over_insert |"
    );
    let _ = writeln!(md, "| ---: | ---: | ---: | ---: | ---: | ---: |");
    let _ = writeln!(
        md,
        "| {} | {} | {} | {} | {} | {} |\n",
        num(r.bvh_over_embree_trace),
        num(r.bvh_over_embree_high_trace),
        num(r.bvh_over_embree_build),
        num(r.bvh_rebuild_over_insert),
        num(r.bvh_insert_sah_over_rebuild),
        num(r.embree_rebuild_over_insert)
    );
    let _ = writeln!(
        md,
        "Integration forms on the same rays, the last island awake (trace over every body \
         instanced):\n"
    );
    let _ = writeln!(md, "| backend | resting | baked |");
    let _ = writeln!(md, "| --- | ---: | ---: |");
    for (backend, resting, baked) in [
        ("embree", r.embree_resting_trace_over_instanced, r.embree_baked_trace_over_instanced),
        ("bvh", r.bvh_resting_trace_over_instanced, r.bvh_baked_trace_over_instanced),
    ] {
        if resting.is_finite() || baked.is_finite() {
            let _ = writeln!(md, "| {backend} | {} | {} |", num(resting), num(baked));
        }
    }
    let _ = writeln!(md);
}

/// "saves 1.20 ms" for a positive saving, "costs 0.35 ms" for a negative one.
fn saves_or_costs(saving_ms: f64) -> String {
    if saving_ms >= 0.0 {
        format!("saves {saving_ms:.2} ms")
    } else {
        format!("costs {:.2} ms", -saving_ms)
    }
}

/// "Every frame", "Every 3rd frame".
fn every(step: u32) -> String {
    match step {
        0 | 1 => "Every frame".into(),
        2 => "Every 2nd frame".into(),
        3 => "Every 3rd frame".into(),
        n => format!("Every {n}th frame"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_regime_map_joins_paper_md_when_its_directory_holds_one() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(regime_section(dir.path()).unwrap(), "", "no regime map, no section");
        let regimes = dir.path().join(REGIMES_DIR);
        std::fs::create_dir_all(&regimes).unwrap();
        std::fs::write(regimes.join("regimes.md"), "| table |\n").unwrap();
        std::fs::write(regimes.join("summary.md"), "When it pays.\n").unwrap();
        let md = regime_section(dir.path()).unwrap();
        let summary = md.find("When it pays.").unwrap();
        let figure = md.find("](regimes/regimes.png)").unwrap();
        let reuse = md.find("](regimes/regimes-reuse.png)").unwrap();
        let table = md.find("| table |").unwrap();
        assert!(
            md.starts_with("## Where integration pays")
                && summary < figure
                && figure < reuse
                && reuse < table,
            "{md}"
        );
    }
}
