"""What every Drake workcell shares: model paths, the parser, port messages, the executor system."""
