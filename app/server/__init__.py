"""Server-wide parts of the dashboard: settings, map jobs and their fair queue, process pools."""
