"""The dashboard's views: each subscribes to the session events it draws."""
