"""citygen studio: a local web application for authoring rulesets live on a scene's buildings (docs/studio.md)."""
