"""First-party footprint importers for citygen: GeoJSON and CityJSON (see docs/footprints.md)."""
