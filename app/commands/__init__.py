"""One module per `nift` verb."""
