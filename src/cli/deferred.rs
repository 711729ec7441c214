//! Deferred subcommand arguments: each subcommand's arguments are declared
//! to clap only when that subcommand is parsed or its help is asked for,
//! every flag that takes a value accepts a negative number, and the
//! subcommand keeps its own help text.

use clap::{ArgMatches, Args, FromArgMatches};

/// A subcommand's arguments, declared to clap only when that subcommand
/// is parsed or its help is asked for (`clap::Command::defer`): a run
/// does not pay for the arguments of the subcommands it does not use.
#[derive(Debug, Clone)]
pub(super) struct Deferred<T>(pub(super) T);

impl<T> std::ops::Deref for Deferred<T> {
    type Target = T;

    fn deref(&self) -> &T {
        &self.0
    }
}

impl<T: FromArgMatches> FromArgMatches for Deferred<T> {
    fn from_arg_matches(matches: &ArgMatches) -> std::result::Result<Self, clap::Error> {
        T::from_arg_matches(matches).map(Deferred)
    }

    fn update_from_arg_matches(
        &mut self,
        matches: &ArgMatches,
    ) -> std::result::Result<(), clap::Error> {
        self.0.update_from_arg_matches(matches)
    }
}

impl<T: Args> Args for Deferred<T> {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        cmd.defer(augment_keeping_about::<T, false>)
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        cmd.defer(augment_keeping_about::<T, true>)
    }
}

/// `T`'s arguments added to `cmd` (for an update with `UPDATE`), with
/// negative numbers accepted as the value of every flag that takes one
/// (`--tau -1` reaches the model's own check; a switch such as `--json`
/// takes none, and clap refuses the setting on it), keeping the
/// subcommand's own help text: the documentation of the groups of
/// arguments it flattens, declared after it, would otherwise replace it.
fn augment_keeping_about<T: Args, const UPDATE: bool>(cmd: clap::Command) -> clap::Command {
    let (about, long_about) = (cmd.get_about().cloned(), cmd.get_long_about().cloned());
    let cmd = if UPDATE {
        T::augment_args_for_update(cmd)
    } else {
        T::augment_args(cmd)
    };
    let cmd = cmd.mut_args(|arg| {
        if arg.get_action().takes_values() {
            arg.allow_negative_numbers(true)
        } else {
            arg
        }
    });
    let cmd = match about {
        Some(about) => cmd.about(about),
        None => cmd.about(None::<&str>),
    };
    match long_about {
        Some(long_about) => cmd.long_about(long_about),
        None => cmd.long_about(None::<&str>),
    }
}
