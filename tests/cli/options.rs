//! Options every subcommand shares the parsing of: a bad value fails before any work, with a
//! message that names the option and what it takes.

use super::*;

#[test]
fn bad_options_fail_with_a_helpful_message() {
    let dir = work_dir("bad_options");
    let scene = write(&dir, "good.json", GOOD_SCENE);
    let out_file = dir.join("out.json");

    let out = myriad_fails(&[
        "assign".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--method".as_ref(),
        "fancy".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert_mentions(
        &out,
        &[
            "unknown method",
            "fancy",
            "exact",
            "linear",
            "binary",
            "refined",
        ],
    );
    assert!(!out_file.exists(), "no dump is written for a bad method");

    let out = myriad_fails(&["bench", "--preset", "paper", "--methods", "refined,bogus"]);
    assert_mentions(&out, &["unknown method", "bogus"]);
    // Counts past what a run can hold aborted on a 32 GiB allocation or slept forever, and a
    // method listed twice was timed twice (audit g2).
    assert_rejected(&[
        (
            &["bench", "--preset", "paper", "--runs", "4294967296"],
            &["--runs", "1..=1000000"],
        ),
        (
            &[
                "bench",
                "--preset",
                "paper",
                "--idle-us",
                "18446744073709551615",
            ],
            &["--idle-us", "0..=1000000"],
        ),
        (
            &[
                "bench",
                "--preset",
                "paper",
                "--methods",
                "binary,refined,binary",
            ],
            &["--methods lists binary twice"],
        ),
    ]);

    let out = myriad_fails(&[
        "scene".as_ref(),
        "--preset".as_ref(),
        "nope".as_ref(),
        "--out".as_ref(),
        out_file.as_os_str(),
    ]);
    assert_mentions(
        &out,
        &["unknown preset", "nope", "paper", "uniform", "sphere"],
    );
    assert!(!out_file.exists());

    let out = myriad_fails(&["bench", "--preset", "nope"]);
    assert_mentions(&out, &["unknown preset", "nope"]);

    // No scene at all, and an unknown flag (clap's own message).
    let out = myriad_fails(&["bench"]);
    assert_mentions(&out, &["--scene", "--preset"]);
    let out = myriad_fails(&["check", "--frobnicate"]);
    assert_mentions(&out, &["--frobnicate"]);
}
