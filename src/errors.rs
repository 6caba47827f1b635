//! Error rendering for the binary: the cause chain on one line, recognition of a closed
//! output pipe, and [`UsageError`], the mark of a wrong command line (exit status 2).
//!
//! Every error of the workspace names only its own context (operation, file, option, value)
//! and leaves the underlying error to `source()`, so the chain that `anyhow`'s `{:#}` prints
//! states each reason once; the one exception, bf-scene's `SpecError::Io`, states its cause
//! in its message and has no source (a build script prints it alone).

/// A wrong command line that the argument parser could not see: an option's value out of its
/// range, an unknown name, or options that do not go together. The binary exits with status 2
/// for it, as clap does for the arguments it rejects itself, so that a script can tell a wrong
/// call (2) from a run that failed or did not verify (1). A file that cannot be read, or whose
/// content does not fit, is not a usage error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// A [`UsageError`] with the message `msg`, as the commands return their errors.
pub fn usage(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(UsageError(msg.into()))
}

/// Returns early from a command with a [`UsageError`] formatted like `format!`.
macro_rules! bail_usage {
    ($($arg:tt)*) => {
        return Err($crate::errors::usage(format!($($arg)*)))
    };
}
pub(crate) use bail_usage;

/// Whether `e` or one of its causes is a [`UsageError`].
pub fn is_usage(e: &anyhow::Error) -> bool {
    // `downcast_ref` also finds a `UsageError` attached as context, the chain one underneath.
    e.downcast_ref::<UsageError>().is_some()
        || e.chain().any(|c| c.downcast_ref::<UsageError>().is_some())
}

/// The error and its causes, joined by `": "`.
pub fn render(e: &anyhow::Error) -> String {
    format!("{e:#}")
}

/// [`render`] for any error: `e` and its causes on one line, joined by `": "`, for a message
/// that is stored or printed as text (a stage record, a warning, a `FAILED` marker).
pub fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        out.push_str(": ");
        out.push_str(&c.to_string());
        cause = c.source();
    }
    out
}

/// Whether the error (or one of its causes) is a write to a closed pipe.
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            || c.downcast_ref::<bf_output::OutputError>()
                .is_some_and(|o| o.kind() == Some(std::io::ErrorKind::BrokenPipe))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::PipelineError;

    fn io() -> std::io::Error {
        std::io::Error::from(std::io::ErrorKind::AlreadyExists)
    }

    #[test]
    fn a_usage_error_is_found_under_context_and_nothing_else_is_one() {
        let e = usage("--points must be at least 2 (got 0)").context("optimize");
        assert!(is_usage(&e));
        assert_eq!(render(&e), "optimize: --points must be at least 2 (got 0)");
        let not: anyhow::Error = io().into();
        assert!(!is_usage(&not.context("--warm-start x.json")));
        let attached = anyhow::Error::from(io()).context(UsageError("--param x".into()));
        assert!(is_usage(&attached));
        fn bails() -> anyhow::Result<()> {
            bail_usage!("--eps must be positive (got {})", -1);
        }
        assert!(is_usage(&bails().unwrap_err()));
    }

    #[test]
    fn io_errors_name_the_file_and_print_their_reason_once() {
        let reason = io().to_string();
        let file = || bf_output::FileError::new("cannot write", "out/run.json", io());
        let errors: Vec<anyhow::Error> = vec![
            bf_sim::SimError::from(file()).into(),
            bf_plot::PlotError::from(file()).into(),
            PipelineError::from(file()).into(),
        ];
        for e in errors {
            let r = render(&e.context("cannot write the output"));
            assert_eq!(r.matches(&reason).count(), 1, "{r}");
            assert!(
                r.starts_with("cannot write the output: cannot write out/run.json: "),
                "{r}"
            );
        }
        let model = bf_problem::ProblemError::Model {
            scene: "paper".into(),
            source: bf_codegen::SceneDefect::NoBall.into(),
        };
        let r = render(&PipelineError::from(model).into());
        assert_eq!(
            r,
            "cannot build the model of scene `paper`: scene error: the scene has no [ball]"
        );
    }

    #[test]
    fn a_failed_run_states_its_error_once() {
        // x' = x² from x(0) = 2 blows up at t = 1/2.
        let fail = bf_sim::simulate(
            &bf_sim::toys::BlowUp,
            bf_sim::SimSettings::default(),
            (),
            0.0,
            &[2.0],
            1.0,
        )
        .unwrap_err();
        let inner = fail.error.to_string();
        let r = chain(&*fail);
        assert!(r.starts_with("simulation failed at t = "), "{r}");
        assert_eq!(r.matches(&inner).count(), 1, "{r}");
    }

    #[test]
    fn a_closed_pipe_is_recognised_through_context() {
        let e = anyhow::Error::new(io()).context("cannot write the output");
        assert!(!is_broken_pipe(&e));
        let pipe = anyhow::Error::new(std::io::Error::from(std::io::ErrorKind::BrokenPipe))
            .context("cannot write to standard output");
        assert!(is_broken_pipe(&pipe));
    }
}
