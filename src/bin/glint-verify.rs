//! `glint-verify`: run the verification harness and write `target/verify/report.md`
//! and `report.json`.
//!
//! Usage: `glint-verify [--all | --lobe NAME | --material NAME | --plugin PATH]... [--fast]
//! [--out DIR]` (default: every registered lobe and material type, full tier,
//! `target/verify`). `--plugin` loads a plugin and verifies its lobe types (all of them
//! unless `--lobe` names some).
//! Exits 1 when a check fails, 2 when a plugin does not load.

use glint::registry::Registry;
use glint::verify::{self, Report, Tier};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut registry = Registry::with_builtins();
    let mut plugin_lobes: Vec<u32> = Vec::new();
    let mut tier = Tier::Full;
    let mut names: Vec<String> = Vec::new();
    let mut materials: Vec<String> = Vec::new();
    let mut out = PathBuf::from("target/verify");
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--all" => {
                names.clear();
                materials.clear();
            }
            "--fast" => tier = Tier::Fast,
            "--lobe" => match args.next() {
                Some(n) => names.push(n),
                None => return usage("--lobe needs a name"),
            },
            "--material" => match args.next() {
                Some(n) => materials.push(n),
                None => return usage("--material needs a name"),
            },
            "--plugin" => match args.next() {
                Some(path) => match glint::plugin::load(&mut registry, Path::new(&path)) {
                    Ok(ids) => plugin_lobes.extend(ids),
                    Err(e) => {
                        eprintln!("glint-verify: {}", e.message);
                        return ExitCode::from(2);
                    }
                },
                None => return usage("--plugin needs a path"),
            },
            "--out" => match args.next() {
                Some(d) => out = PathBuf::from(d),
                None => return usage("--out needs a directory"),
            },
            "-h" | "--help" => return usage(""),
            other => return usage(&format!("unknown argument {other}")),
        }
    }
    let mut lobes = Vec::new();
    let mut material_ids = Vec::new();
    for n in &materials {
        match registry.find_material(n) {
            Ok(id) => material_ids.push(id),
            Err(e) => return usage(&e.message),
        }
    }
    if names.is_empty() && !plugin_lobes.is_empty() {
        lobes.extend(plugin_lobes.iter().filter_map(|&id| registry.get(id).ok()));
    } else if names.is_empty() && materials.is_empty() {
        lobes.extend(registry.iter());
        material_ids.extend(0..registry.materials().len() as u32);
    } else {
        for n in &names {
            match registry.find(n).and_then(|id| registry.get(id)) {
                Ok(l) => lobes.push(l),
                Err(e) => return usage(&e.message),
            }
        }
    }
    let mut reports: Vec<_> = lobes
        .into_iter()
        .map(|l| {
            eprintln!("verifying {} ({tier:?} tier)...", l.name());
            verify::verify_lobe(l, tier)
        })
        .collect();
    reports.extend(material_ids.into_iter().map(|id| {
        eprintln!("verifying material type {id} ({tier:?} tier)...");
        verify::verify_material(id, tier)
    }));
    let report = Report::new(tier, reports);
    if let Err(e) = std::fs::create_dir_all(&out)
        .and_then(|_| std::fs::write(out.join("report.md"), report.to_markdown()))
        .and_then(|_| std::fs::write(out.join("report.json"), report.to_json().to_string()))
    {
        eprintln!(
            "glint-verify: cannot write the report to {}: {e}",
            out.display()
        );
        return ExitCode::from(2);
    }
    print!("{}", report.to_markdown());
    println!(
        "\nreport: {}/report.md, {}/report.json",
        out.display(),
        out.display()
    );
    if report.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

fn usage(problem: &str) -> ExitCode {
    if !problem.is_empty() {
        eprintln!("glint-verify: {problem}");
    }
    eprintln!(
        "usage: glint-verify [--all | --lobe NAME | --material NAME | --plugin PATH]... [--fast] [--out DIR]"
    );
    ExitCode::from(2)
}
