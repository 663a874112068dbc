//! Render farms. `--samples auto` and `--shard auto` take the task from a Slurm job array's or a
//! Kubernetes Indexed Job's environment; `pathwave farm merge` names the shares that are missing
//! or unfinished and writes nothing; the Kubernetes example in docs/ renders what one machine
//! renders; and on a real one-node Slurm, started here (munged, slurmctld and slurmd on the
//! loopback address, in a temporary folder), `pathwave farm slurm` renders a 4-task sample
//! split and a 3-task sharded sequence to the bytes of one machine's renders, also when a task
//! is killed mid-way and requeued. That test needs Slurm, munge and root (slurmd starts jobs as
//! their user), so it is ignored unless asked for (`cargo test --release --test farm --
//! --ignored`, as `.ci/run` does); asked for where it cannot run, it fails saying what is missing.

mod common;
use common::root;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The environment variables a task reads its share from.
const TASK_VARS: [&str; 6] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_STEP",
    "SLURM_ARRAY_TASK_COUNT",
    "JOB_COMPLETION_INDEX",
    "PATHWAVE_SHARD_COUNT",
];

/// pathwave, run from the repository, not a task of whatever runs the tests.
fn pathwave() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pathwave"));
    c.current_dir(root());
    for v in TASK_VARS {
        c.env_remove(v);
    }
    c
}

/// Runs `c`, which must succeed; its stdout and stderr.
fn run(c: &mut Command) -> String {
    let out = c.output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{c:?} failed:\n{text}");
    text
}

/// Runs `c`, which must fail; its stderr.
fn fails(c: &mut Command) -> String {
    let out = c.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "{c:?} succeeded:\n{err}");
    err
}

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pathwave-farm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Frame files `[0, n)` of two folders of `f_{frame:04}.png` have the same bytes.
fn same_frames(a: &Path, b: &Path, n: u32) {
    for f in 0..n {
        let name = format!("f_{f:04}.png");
        assert!(bytes(&a.join(&name)) == bytes(&b.join(&name)), "frame {f} differs: {}", b.display());
    }
}

#[test]
fn shares_come_from_slurm_or_kubernetes_environments() {
    let dir = temp("auto");
    let share = |out: &str, extra: &[&str]| {
        let mut c = pathwave();
        c.args(["render", "scenes/cornell.ron", "--width", "16", "--height", "16", "--spp", "4", "-q"])
            .arg("-o")
            .arg(dir.join(out))
            .args(extra);
        c
    };
    let none = fails(&mut share("x.exr", &["--samples", "auto"]));
    assert!(none.contains("neither SLURM_ARRAY_TASK_ID") && none.contains("--samples A..B"), "{none}");
    let uncounted = fails(share("x.exr", &["--samples", "auto"]).env("JOB_COMPLETION_INDEX", "1"));
    assert!(uncounted.contains("--shard-count N or set PATHWAVE_SHARD_COUNT"), "{uncounted}");
    // Share 1 of 2 is samples 2..4, whoever says so.
    run(share("k8s.exr", &["--samples", "auto"])
        .env("JOB_COMPLETION_INDEX", "1")
        .env("PATHWAVE_SHARD_COUNT", "2"));
    run(share("slurm.exr", &["--samples", "auto"])
        .env("SLURM_ARRAY_TASK_ID", "1")
        .env("SLURM_ARRAY_TASK_MIN", "0")
        .env("SLURM_ARRAY_TASK_COUNT", "2"));
    run(&mut share("range.exr", &["--samples", "2..4"]));
    let range = bytes(&dir.join("range.exr.ckpt"));
    assert!(bytes(&dir.join("k8s.exr.ckpt")) == range && bytes(&dir.join("slurm.exr.ckpt")) == range);

    // Frames: task 1 of 3 renders frames 1 and 4 of 0..6 (an array numbered from 4 here).
    let frames = |pattern: &Path| {
        let mut c = pathwave();
        c.args(["animate", "scenes/animation-bounce.ron", "--width", "16", "--height", "12", "--spp", "1"])
            .args(["-q", "--frames", "0..6", "--shard", "auto", "-o", pattern.to_str().unwrap()]);
        c
    };
    let k8s = dir.join("k8s/f{frame}.png");
    run(frames(&k8s).env("JOB_COMPLETION_INDEX", "1").args(["--shard-count", "3"]));
    let slurm = dir.join("slurm/f{frame}.png");
    run(frames(&slurm)
        .env("SLURM_ARRAY_TASK_ID", "5")
        .env("SLURM_ARRAY_TASK_MIN", "4")
        .env("SLURM_ARRAY_TASK_STEP", "1")
        .env("SLURM_ARRAY_TASK_COUNT", "3"));
    for sub in ["k8s", "slurm"] {
        let mut names: Vec<String> = std::fs::read_dir(dir.join(sub))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["f1.png", "f4.png"], "{sub}");
    }
    // The merge job of that sequence names the other two tasks' frames.
    let missing =
        fails(pathwave().args(["farm", "merge", "--tasks", "3", "--frames", "0..6", "-o"]).arg(&k8s));
    assert!(missing.contains("task 0 (frame 0 and every 3 after it): frames 0, 3 missing"), "{missing}");
    assert!(missing.contains("task 2 (frame 2 and every 3 after it): frames 2, 5 missing"), "{missing}");
    assert!(!missing.contains("task 1"), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_merge_names_missing_and_unfinished_shares_and_writes_nothing() {
    let dir = temp("merge");
    let (parts, out, single) = (dir.join("parts"), dir.join("out.png"), dir.join("single.png"));
    std::fs::create_dir_all(&parts).unwrap();
    let small = ["scenes/cornell.ron", "--width", "32", "--height", "32", "--spp", "16", "-q"];
    let share = |task: u32, samples: &str| {
        let mut c = pathwave();
        c.arg("render").args(small).args(["--resume", "--samples", samples, "-o"]);
        c.arg(parts.join(format!("task-{task}.exr")))
            .env("JOB_COMPLETION_INDEX", task.to_string())
            .env("PATHWAVE_SHARD_COUNT", "4");
        c
    };
    let merge = || {
        let mut c = pathwave();
        c.args(["farm", "merge", "--tasks", "4", "--spp", "16", "--parts"]).arg(&parts).arg("-o").arg(&out);
        c
    };
    run(&mut share(0, "auto"));
    run(&mut share(3, "auto"));
    // Task 1 stopped after 2 of its 4 samples (4..8); task 2 never ran.
    run(&mut share(1, "4..6"));
    let err = fails(&mut merge());
    assert!(err.contains("shares not ready (2 of 4), so nothing is merged"), "{err}");
    assert!(err.contains("task 1 (samples 4..8): unfinished, 2 of its 4 samples per pixel"), "{err}");
    assert!(err.contains("task 2 (samples 8..12):") && err.contains("task-2.exr.ckpt is missing"), "{err}");
    assert!(!err.contains("task 0") && !err.contains("task 3"), "{err}");
    assert!(!out.exists(), "the merge wrote a partial image");

    // Run again, task 1 resumes where it stopped and task 0 only writes its share out again.
    assert!(run(&mut share(1, "auto")).contains("resuming samples 4..8 at 6"));
    run(&mut share(2, "auto"));
    assert!(run(&mut share(0, "auto")).contains("complete (4 spp)"));
    run(&mut merge());
    run(pathwave().arg("render").args(small).arg("-o").arg(&single));
    assert!(bytes(&out) == bytes(&single), "the merged image differs from one render");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_guided_image_learns_its_guides_once_for_every_share() {
    let dir = temp("guided");
    let scene = dir.join("cornell.ron");
    std::fs::copy(root().join("scenes/cornell.ron"), &scene).unwrap();
    let (out, single) = (dir.join("out.png"), dir.join("single.png"));
    let flags = ["--width", "32", "--height", "24", "--spp", "8", "--guiding", "on"];
    let mut c = pathwave();
    c.args(["farm", "slurm"]).arg(&scene).arg("-o").arg(&out).args(["--split-samples", "--tasks", "2"]);
    let printed = run(c.args(flags).arg("--dry-run"));
    // A training job, then the array after it, then the merge.
    let train = printed.find("TRAIN=$(sbatch").expect(&printed);
    assert!(printed[train..].contains("RENDER=$(sbatch --parsable --dependency=afterok:$TRAIN"), "{printed}");
    let execs: Vec<&str> = printed.lines().filter(|l| l.starts_with("exec ")).collect();
    assert_eq!(execs.len(), 3, "{printed}");
    assert!(execs[0].contains("--train-only --guide-file") && execs[1].contains("--guide-file"), "{printed}");
    // What Slurm would run: the training job, the two tasks, the merge.
    let job = dir.join("out.png.farm");
    for sub in ["logs", "parts"] {
        std::fs::create_dir_all(job.join(sub)).unwrap();
    }
    let shell = |line: &str, task: Option<u32>| {
        let mut c = Command::new("sh");
        c.args(["-c", line]).current_dir(root());
        for v in TASK_VARS {
            c.env_remove(v);
        }
        if let Some(t) = task {
            c.env("SLURM_ARRAY_TASK_ID", t.to_string()).env("SLURM_ARRAY_TASK_COUNT", "2");
        }
        run(&mut c)
    };
    shell(execs[0], None);
    assert!(job.join("guides.bin").exists());
    for t in 0..2 {
        let said = shell(execs[1], Some(t));
        assert!(said.contains("the guides read (no training)"), "task {t}: {said}");
    }
    shell(execs[2], None);
    run(pathwave().arg("render").arg(&scene).args(flags).arg("-q").arg("-o").arg(&single));
    assert!(bytes(&out) == bytes(&single), "the merged image differs from one render");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_dry_run_prints_the_jobs_with_the_render_flags() {
    let dir = temp("dry");
    let scene = dir.join("p.ron");
    std::fs::write(
        &scene,
        r#"Scene(
            parameters: { "wall": "(0.7, 0.7, 0.7)" },
            camera: (look_from: (0, 0, 5), look_at: (0, 0, 0), vfov: 40),
            render: (width: 8, height: 8, spp: 4),
            background: Constant((1, 1, 1)),
            materials: { "white": Lambertian(albedo: $wall) },
            objects: [(shape: Sphere(center: (0, 0, 0), radius: 1), material: "white")],
        )"#,
    )
    .unwrap();
    let pattern = dir.join("out/f_{frame:03}.exr");
    let farm = |extra: &[&str]| {
        let mut c = pathwave();
        c.args(["farm", "slurm"]).arg(&scene).arg("-o").arg(&pattern).args(extra);
        c
    };
    let printed = run(farm(&["--tasks", "2", "--frames", "0..4", "--spp", "2", "--aov", "depth"])
        .args(["-D", "wall=(0.1, 0.2, 0.3)", "-vv", "--partition", "debug", "--time", "5:00"])
        .args(["--dry-run", "--", "--mem=1G"]));
    let job = dir.join("out/f_frames.exr.farm");
    for expected in [
        format!("# {}/render.sbatch", job.display()),
        "#SBATCH --array=0-1".into(),
        "#SBATCH --requeue".into(),
        "#SBATCH --partition=debug".into(),
        "#SBATCH --time=5:00".into(),
        format!("#SBATCH --output={}/logs/task-%a.log", job.display()),
        format!("-o '{}' --frames 0..4 --shard auto --shard-count 2", pattern.display()),
        "--spp=2 '-Dwall=(0.1, 0.2, 0.3)' --aov=depth --verbose --verbose".into(),
        // A scene sent to a farm reads files from its own folder only, unless told otherwise.
        format!("--assets-under={}", dir.display()),
        format!("farm merge -o '{}' --tasks 2 --frames 0..4", pattern.display()),
        "RENDER=$(sbatch --parsable --mem=1G ".into(),
        "sbatch --dependency=afterok:$RENDER --kill-on-invalid-dep=yes --mem=1G ".into(),
    ] {
        assert!(printed.contains(&expected), "no {expected:?} in:\n{printed}");
    }
    assert!(!job.exists() && !dir.join("out").exists(), "a dry run wrote files");

    // Refused before anything is written or submitted.
    let still = dir.join("still.png");
    let still = still.to_str().unwrap();
    for (extra, says) in [
        (&["--tasks", "5", "--frames", "0..4"][..], "frames 0..4 keep at most 4 tasks busy"),
        (&["--tasks", "2", "--frames", "0..4", "--time", "1 day"], "not a Slurm time"),
        (&["--tasks", "2", "--frames", "0..4", "--fps", "0"], "--fps takes a number > 0"),
        (&["--tasks", "2", "--frames", "0..4", "--trace", "t.json"], "every task would write the same file"),
    ] {
        let err = fails(&mut farm(extra));
        assert!(err.contains(says), "{extra:?}: {err}");
    }
    let split = |extra: &[&str]| {
        fails(pathwave().args(["farm", "slurm"]).arg(&scene).args(["-o", still]).args(extra))
    };
    let err = split(&["--tasks", "5", "--split-samples"]);
    assert!(err.contains("the 4 samples per pixel make at most 4 shares"), "{err}");
    let err = split(&["--tasks", "2", "--split-samples", "--denoise"]);
    assert!(err.contains("it does not denoise"), "{err}");
    let err = split(&["--tasks", "2"]);
    assert!(err.contains("needs {frame}") && err.contains("--split-samples"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The block scalars (`- |`) of a YAML document: the shell scripts its containers run.
fn scripts(doc: &str) -> Vec<String> {
    let lines: Vec<&str> = doc.lines().collect();
    let indent = |l: &str| l.len() - l.trim_start().len();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if l.trim() != "- |" {
            continue;
        }
        let body: Vec<&str> = lines[i + 1..]
            .iter()
            .take_while(|b| b.trim().is_empty() || indent(b) > indent(l))
            .copied()
            .collect();
        let cut = body.iter().filter(|b| !b.trim().is_empty()).map(|b| indent(b)).min().unwrap_or(0);
        out.push(body.iter().map(|b| b.get(cut..).unwrap_or("")).collect::<Vec<_>>().join("\n"));
    }
    out
}

/// The value of `key: value` in a YAML document, if any.
fn field<'a>(doc: &'a str, key: &str) -> Option<&'a str> {
    doc.lines()
        .find_map(|l| l.trim().strip_prefix(key)?.strip_prefix(':'))
        .map(|v| v.trim().trim_matches('"'))
}

#[test]
fn the_kubernetes_example_renders_what_one_machine_renders() {
    // docs/kubernetes.yaml's Indexed Jobs, then docs/kubernetes-merge.yaml's Job, each pod's
    // script run with JOB_COMPLETION_INDEX set as Kubernetes sets it, in a folder standing for
    // the shared volume (`workingDir`), with pathwave on the PATH as in the image.
    let data = temp("k8s");
    std::os::unix::fs::symlink(root().join("scenes"), data.join("scenes")).unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_pathwave")).parent().unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let mut pods = 0;
    for file in ["docs/kubernetes.yaml", "docs/kubernetes-merge.yaml"] {
        let text = std::fs::read_to_string(root().join(file)).unwrap();
        for doc in text.split("\n---\n").filter(|d| field(d, "kind") == Some("Job")) {
            let indexed = field(doc, "completionMode") == Some("Indexed");
            let completions: u32 = field(doc, "completions").map_or(1, |c| c.parse().unwrap());
            if indexed {
                // The pods' count of shares must be the Job's.
                let count = doc.lines().skip_while(|l| !l.contains("name: PATHWAVE_SHARD_COUNT")).nth(1);
                let count = count.and_then(|l| field(l, "value")).unwrap_or_else(|| panic!("{file}: {doc}"));
                assert_eq!(count, completions.to_string(), "{file}: PATHWAVE_SHARD_COUNT is not completions");
            }
            let script = scripts(doc);
            assert_eq!(script.len(), 1, "{file}: one script a pod:\n{doc}");
            for index in 0..completions {
                let mut c = Command::new("sh");
                c.arg("-c").arg(&script[0]).current_dir(&data).env("PATH", &path);
                for v in TASK_VARS {
                    c.env_remove(v);
                }
                if indexed {
                    c.env("JOB_COMPLETION_INDEX", index.to_string())
                        .env("PATHWAVE_SHARD_COUNT", completions.to_string());
                }
                run(&mut c);
                pods += 1;
            }
        }
    }
    assert_eq!(pods, 3 + 4 + 1, "the example's pods");
    // One machine, the same flags.
    let single = data.join("single");
    run(pathwave().args(["animate", "scenes/animation-bounce.ron", "--frames", "0..12"]).args([
        "--width",
        "64",
        "--height",
        "48",
        "--spp",
        "4",
        "-q",
        "-o",
        single.join("f_{frame:04}.png").to_str().unwrap(),
    ]));
    same_frames(&single, &data.join("out/frames"), 12);
    let still = single.join("cornell.png");
    run(pathwave()
        .args(["render", "scenes/cornell.ron", "--width", "64", "--height", "64", "--spp", "16", "-q", "-o"])
        .arg(&still));
    assert!(
        bytes(&still) == bytes(&data.join("out/cornell.png")),
        "the merged image differs from one render"
    );
    std::fs::remove_dir_all(&data).unwrap();
}

/// A one-node Slurm cluster on this machine: munged, slurmctld and slurmd on the loopback
/// address, their configuration, keys, state and logs in a temporary folder. Dropping it
/// cancels its jobs and stops each daemon by its process id.
struct Slurm {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

impl Slurm {
    /// Starts the daemons and waits for the node to be idle; fails saying what is missing where
    /// Slurm or munge is not installed or the tests do not run as root.
    fn start() -> Slurm {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        use std::os::unix::process::CommandExt;
        let find = |name: &str| {
            let path = std::env::var("PATH").unwrap_or_default();
            let dirs =
                path.split(':').map(PathBuf::from).chain(["/usr/sbin", "/usr/local/sbin"].map(PathBuf::from));
            dirs.map(|d| d.join(name)).find(|p| p.is_file())
        };
        let tools = ["munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "sinfo", "scancel"];
        let missing: Vec<&str> = tools.into_iter().filter(|t| find(t).is_none()).collect();
        assert!(
            missing.is_empty(),
            "cannot run: Slurm and munge are not installed (no {}); on Debian: apt-get install \
             slurmctld slurmd slurm-client munge",
            missing.join(", ")
        );
        assert!(
            std::fs::metadata("/proc/self").is_ok_and(|m| m.uid() == 0),
            "cannot run: a Slurm cluster needs root (slurmd starts jobs as their user)"
        );
        let passwd = std::fs::read_to_string("/etc/passwd").unwrap_or_default();
        let munge = passwd.lines().find_map(|l| {
            let f: Vec<&str> = l.split(':').collect();
            (f.len() > 3 && f[0] == "munge").then(|| (f[2].parse::<u32>().ok(), f[3].parse::<u32>().ok()))
        });
        let Some((Some(uid), Some(gid))) = munge else {
            panic!("cannot run: there is no munge user (the munge package makes it)");
        };
        let dir = temp("slurm");
        // munged runs as the munge user: it must reach its folder, whose socket all must reach.
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
        let mdir = dir.join("munge");
        std::fs::create_dir(&mdir).unwrap();
        std::os::unix::fs::chown(&mdir, Some(uid), Some(gid)).unwrap();
        std::fs::set_permissions(&mdir, std::fs::Permissions::from_mode(0o711)).unwrap();
        let key = mdir.join("munge.key");
        let mut random = vec![0u8; 1024];
        std::io::Read::read_exact(&mut std::fs::File::open("/dev/urandom").unwrap(), &mut random).unwrap();
        std::fs::write(&key, &random).unwrap();
        std::os::unix::fs::chown(&key, Some(uid), Some(gid)).unwrap();
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).unwrap();
        let socket = mdir.join("munge.socket");
        let mut slurm = Slurm { conf: dir.join("slurm.conf"), dir: dir.clone(), daemons: Vec::new() };
        let mut munged = Command::new(find("munged").unwrap());
        munged.arg("--foreground").arg("--socket").arg(&socket).arg("--key-file").arg(&key);
        munged.arg("--pid-file").arg(mdir.join("munged.pid")).arg("--log-file").arg(mdir.join("munged.log"));
        munged.arg("--seed-file").arg(mdir.join("munged.seed")).uid(uid).gid(gid);
        slurm.spawn("munged", &mut munged);
        slurm.until("munged's socket", || socket.exists());

        // Two free ports on the loopback address.
        let free = || std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let (ctld_port, slurmd_port) = (free(), free());
        let d = dir.display();
        for sub in ["state", "spool", "log"] {
            std::fs::create_dir(dir.join(sub)).unwrap();
        }
        std::fs::write(
            &slurm.conf,
            format!(
                "ClusterName=pathwave\nSlurmctldHost=localhost(127.0.0.1)\n\
                 SlurmctldPort={ctld_port}\nSlurmdPort={slurmd_port}\nSlurmUser=root\n\
                 AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket={}\n\
                 StateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
                 SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
                 SlurmctldLogFile={d}/log/slurmctld.log\nSlurmdLogFile={d}/log/slurmd.log\n\
                 ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
                 SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n\
                 JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n\
                 MpiDefault=none\nReturnToService=2\nMinJobAge=600\nKillWait=2\n\
                 NodeName=farmnode NodeAddr=127.0.0.1 NodeHostname=localhost CPUs=2 State=UNKNOWN\n\
                 PartitionName=farm Nodes=farmnode Default=YES MaxTime=INFINITE State=UP\n",
                socket.display()
            ),
        )
        .unwrap();
        let mut ctld = Command::new(find("slurmctld").unwrap());
        ctld.args(["-D", "-i"]).env("SLURM_CONF", &slurm.conf);
        slurm.spawn("slurmctld", &mut ctld);
        let mut slurmd = Command::new(find("slurmd").unwrap());
        slurmd.args(["-D", "-N", "farmnode"]).env("SLURM_CONF", &slurm.conf);
        slurm.spawn("slurmd", &mut slurmd);
        slurm.until("the node to be idle", || {
            slurm
                .command("sinfo")
                .args(["-h", "-n", "farmnode", "-o", "%T"])
                .output()
                .is_ok_and(|o| o.stdout.starts_with(b"idle"))
        });
        slurm
    }

    fn spawn(&mut self, name: &'static str, c: &mut Command) {
        let log = std::fs::File::create(self.dir.join(format!("{name}.out"))).unwrap();
        let child = c.stdin(Stdio::null()).stdout(log.try_clone().unwrap()).stderr(log).spawn().unwrap();
        self.daemons.push((name, child));
    }

    /// A Slurm client command talking to this cluster.
    fn command(&self, name: &str) -> Command {
        let mut c = Command::new(name);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// Waits up to a minute for `done`, failing with the daemons' logs if they stopped.
    fn until(&self, what: &str, mut done: impl FnMut() -> bool) {
        let start = Instant::now();
        while !done() {
            if start.elapsed() > Duration::from_secs(60) {
                panic!("waited a minute for {what}\n{}", self.logs());
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The daemons' logs and the job logs, for failure messages.
    fn logs(&self) -> String {
        let mut out = String::new();
        for name in [
            "munged.out",
            "slurmctld.out",
            "slurmd.out",
            "log/slurmctld.log",
            "log/slurmd.log",
            "munge/munged.log",
        ] {
            let text = std::fs::read_to_string(self.dir.join(name)).unwrap_or_default();
            let tail: Vec<&str> = text.lines().rev().take(15).collect();
            out += &format!("--- {name}\n{}\n", tail.into_iter().rev().collect::<Vec<_>>().join("\n"));
        }
        out
    }

    /// Submits with `pathwave farm slurm ARGS`; the render array's and the merge job's ids.
    fn submit(&self, args: &[&str]) -> (String, String) {
        let text = run(pathwave().args(["farm", "slurm"]).args(args).env("SLURM_CONF", &self.conf));
        let after = |word: &str| {
            let rest = text.split(word).nth(1).unwrap_or_else(|| panic!("no {word:?} in {text}"));
            rest.split_whitespace().next().unwrap().to_string()
        };
        (after("render array "), after("merge job "))
    }

    /// The state of `job` (`PENDING`, `RUNNING`, `COMPLETED`, ...), empty once Slurm forgot it.
    fn state(&self, job: &str) -> String {
        let out = self.command("squeue").args(["-h", "-t", "all", "-j", job, "-o", "%T"]).output().unwrap();
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }

    /// Waits for the jobs to leave the queue, then checks that each succeeded.
    fn wait(&self, jobs: &[&str], logs: &Path) {
        self.settle(jobs, logs);
        for job in jobs {
            let states = self.state(job);
            assert!(
                !states.is_empty() && states.lines().all(|s| s == "COMPLETED"),
                "job {job}: {states}\n{}",
                job_logs(logs)
            );
        }
    }

    /// Waits for the jobs to leave the queue (done, failed or cancelled).
    fn settle(&self, jobs: &[&str], logs: &Path) {
        let list = jobs.join(",");
        let active = || {
            let out = self.command("squeue").args(["-h", "-j", &list, "-o", "%i %T"]).output().unwrap();
            String::from_utf8_lossy(&out.stdout).trim().to_string()
        };
        let start = Instant::now();
        loop {
            let now = active();
            if now.is_empty() {
                break;
            }
            if start.elapsed() > Duration::from_secs(120) {
                panic!("jobs still queued after 2 minutes:\n{now}\n{}\n{}", job_logs(logs), self.logs());
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

/// The farm's task and merge logs in `dir`.
fn job_logs(dir: &Path) -> String {
    let mut out = String::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let text = std::fs::read_to_string(entry.path()).unwrap_or_default();
        out += &format!("--- {}\n{text}\n", entry.path().display());
    }
    out
}

impl Drop for Slurm {
    fn drop(&mut self) {
        let _ = self.command("scancel").args(["--partition", "farm"]).status();
        // Each daemon by its process id, the last started first: SIGTERM (with procps' kill,
        // where there is one), then SIGKILL.
        while let Some((name, mut child)) = self.daemons.pop() {
            let term = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
            let start = Instant::now();
            let running = |c: &mut Child| c.try_wait().ok().flatten().is_none();
            while term.as_ref().is_ok_and(|s| s.success())
                && running(&mut child)
                && start.elapsed().as_secs() < 10
            {
                std::thread::sleep(Duration::from_millis(50));
            }
            if running(&mut child) {
                eprintln!("{name}: stopped with SIGKILL");
                let _ = child.kill();
                let _ = child.wait();
            }
        }
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

#[test]
#[ignore = "needs Slurm, munge and root: cargo test --release --test farm -- --ignored"]
fn slurm_job_arrays_render_the_bits_of_one_machine() {
    let started = Instant::now();
    let slurm = Slurm::start();
    eprintln!("slurm up in {:.1} s", started.elapsed().as_secs_f64());
    let work = slurm.dir.join("work");
    let path = |p: &str| work.join(p).to_str().unwrap().to_string();
    std::fs::create_dir_all(&work).unwrap();

    // A 4-task split of one image's samples and a 3-task split of 12 frames, queued together.
    let still = ["scenes/cornell.ron", "--width", "64", "--height", "64", "--spp", "16", "-t", "1", "-q"];
    let (split, split_merge) = slurm
        .submit(&[&still[..], &["-o", &path("cornell.png"), "--tasks", "4", "--split-samples"]].concat());
    let sequence =
        ["scenes/animation-bounce.ron", "--width", "64", "--height", "48", "--spp", "4", "-t", "1", "-q"];
    let pattern = path("farm/f_{frame:04}.png");
    let (frames, frames_merge) =
        slurm.submit(&[&sequence[..], &["-o", &pattern, "--tasks", "3", "--frames", "0..12"]].concat());
    // One machine, the same flags.
    run(pathwave().arg("render").args(still).args(["-o", &path("single.png")]));
    let single = path("single/f_{frame:04}.png");
    run(pathwave().arg("animate").args(sequence).args(["-o", &single, "--frames", "0..12"]));
    slurm.wait(&[&split, &split_merge], &work.join("cornell.png.farm/logs"));
    assert!(bytes(&work.join("cornell.png")) == bytes(&work.join("single.png")), "the merged image differs");
    slurm.wait(&[&frames, &frames_merge], &work.join("farm/f_frames.png.farm/logs"));
    same_frames(&work.join("single"), &work.join("farm"), 12);
    eprintln!("split and sequence done at {:.1} s", started.elapsed().as_secs_f64());

    // Task 2 fails (its share's checkpoint is damaged): Slurm cancels the merge job, whose
    // script, run by hand, names the share. Submitted again, the other tasks only write their
    // shares out again, and the image is the same.
    let parts = work.join("failed.png.farm/parts");
    std::fs::create_dir_all(&parts).unwrap();
    std::fs::write(parts.join("task-2.exr.ckpt"), b"damaged").unwrap();
    let failed = path("failed.png");
    let failing = [&still[..], &["-o", &failed, "--tasks", "4", "--split-samples"]].concat();
    let (array, merge) = slurm.submit(&failing);
    let logs = work.join("failed.png.farm/logs");
    slurm.settle(&[&array, &merge], &logs);
    let states = slurm.state(&array);
    assert_eq!(states.lines().filter(|s| *s == "FAILED").count(), 1, "{states}\n{}", job_logs(&logs));
    assert_eq!(slurm.state(&merge), "CANCELLED", "{}", job_logs(&logs));
    let err = fails(Command::new("sh").arg(work.join("failed.png.farm/merge.sbatch")));
    assert!(
        err.contains("task 2 (samples 8..12): ") && err.contains("not a usable pathwave checkpoint"),
        "{err}"
    );
    assert!(!work.join("failed.png").exists());
    std::fs::remove_file(parts.join("task-2.exr.ckpt")).unwrap();
    let (array, merge) = slurm.submit(&failing);
    slurm.wait(&[&array, &merge], &logs);
    let log = std::fs::read_to_string(logs.join("task-0.log")).unwrap();
    assert!(log.contains("complete (4 spp); writing its image"), "{log}");
    assert!(bytes(&work.join("failed.png")) == bytes(&work.join("single.png")), "the image differs");
    eprintln!("failed task and resubmission done at {:.1} s", started.elapsed().as_secs_f64());

    // Task 1 of a longer split is requeued (killed, then queued again) once it has saved a
    // checkpoint; it resumes from it, and the merge still gives the bits of one render.
    let long = ["scenes/cornell.ron", "--width", "64", "--height", "64", "--spp", "2048", "-q"];
    let mut reference = pathwave();
    let reference = reference.arg("render").args(long).args(["-o", &path("long.png")]);
    let reference = reference.stderr(Stdio::piped()).spawn().unwrap();
    let farm = [
        "-o",
        &path("requeued.png"),
        "--tasks",
        "4",
        "--split-samples",
        "-t",
        "1",
        "--checkpoint-every",
        "0.1",
    ];
    let (array, merge) = slurm.submit(&[&long[..], &farm].concat());
    let ckpt = work.join("requeued.png.farm/parts/task-1.exr.ckpt");
    slurm.until("task 1's first checkpoint", || ckpt.exists());
    let task = format!("{array}_1");
    assert!(slurm.command("scontrol").args(["requeue", &task]).status().unwrap().success());
    let at_kill = pathwave::checkpoint::Checkpoint::load(&ckpt).unwrap().film.spp;
    assert!(at_kill < 512, "task 1 finished before it was requeued");
    // Slurm holds a requeued job back for a while (its begin time); let it start now.
    slurm.until("task 1 to be queued again", || slurm.state(&task) == "PENDING");
    assert!(
        slurm
            .command("scontrol")
            .args(["update", &format!("JobId={task}"), "StartTime=now"])
            .status()
            .unwrap()
            .success()
    );
    let logs = work.join("requeued.png.farm/logs");
    slurm.wait(&[&array, &merge], &logs);
    let reference = reference.wait_with_output().unwrap();
    assert!(reference.status.success(), "{}", String::from_utf8_lossy(&reference.stderr));
    let log = std::fs::read_to_string(logs.join("task-1.log")).unwrap();
    assert!(log.contains("DUE TO JOB REQUEUE") && log.contains("resuming samples 512..1024 at"), "{log}");
    assert!(
        bytes(&work.join("requeued.png")) == bytes(&work.join("long.png")),
        "the image differs after a requeue"
    );
    eprintln!("requeue done at {:.1} s", started.elapsed().as_secs_f64());
}
