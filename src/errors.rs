//! Error rendering for the binary: the cause chain on one line without repeated texts, and
//! recognition of a closed output pipe.
//!
//! Some library errors already include their source's message in their own and also expose
//! the source (`"I/O error on DIR: File exists (os error 17)"` with the `io::Error` as its
//! source), which `anyhow`'s `{:#}` would print twice. [`render`] skips a cause whose text
//! is already part of the message.

/// The error and its causes, joined by `": "`, leaving out every cause whose text already
/// appears in what is printed.
pub fn render(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if text.is_empty() || msg.contains(&text) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&text);
    }
    msg
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

    #[derive(Debug)]
    struct Embeds(std::io::Error);
    impl std::fmt::Display for Embeds {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "I/O error on out/x: {}", self.0)
        }
    }
    impl std::error::Error for Embeds {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn a_source_embedded_in_its_parent_is_printed_once() {
        let io = std::io::Error::from(std::io::ErrorKind::AlreadyExists);
        let text = io.to_string();
        let e = anyhow::Error::new(Embeds(io)).context("cannot write the output");
        let r = render(&e);
        assert_eq!(r.matches(&text).count(), 1, "{r}");
        assert!(
            r.starts_with("cannot write the output: I/O error on out/x"),
            "{r}"
        );
        assert!(!is_broken_pipe(&e));
        let pipe = anyhow::Error::new(std::io::Error::from(std::io::ErrorKind::BrokenPipe))
            .context("cannot write to standard output");
        assert!(is_broken_pipe(&pipe));
    }
}
