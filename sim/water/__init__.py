"""The water: still, regular, irregular and spread seas, measured records."""
