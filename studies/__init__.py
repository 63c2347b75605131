"""Generated documents (the accuracy report, the source report's figures); outputs go to reports/."""
