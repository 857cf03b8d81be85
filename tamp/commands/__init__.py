"""CLI subcommands of `tamp`; one module per subcommand, each with ``register(subparsers)``."""
